"""Every command's ``--help`` read against the code it describes: the recipes, profiles and the device
a fit runs on when none is named."""
import argparse
import re

import pytest
import torch

from ddp_lite.interface.cli import build_parser
from ddp_lite.method import profiles
from ddp_lite.method.kit import recipes
from ddp_lite.method.runtime.device import resolve_device
from ddp_lite.method.runtime.options import RunOptions


def _options(flag):
    """(command, action) for every command that has ``flag``."""
    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    found = [(name, action) for name, parser in commands.items() for action in parser._actions
             if flag in action.option_strings]
    assert found, f"no command has {flag}"
    return found


def test_every_recipe_is_offered_and_explained_and_the_default_is_the_codes():
    for command, action in _options("--recipe"):
        assert tuple(action.choices) == tuple(recipes.RECIPES), command
        for name in recipes.RECIPES:  # "name = what it does", not just the name in a list
            assert re.search(rf"\b{re.escape(name)} = \w", action.help), (command, name)
        if command == "solutions":  # the notebooks' own, as a student runs them (kit; photo in notebook 09)
            assert "else each notebook's own" in action.help, command
        else:
            assert f"else {recipes.DEFAULT})" in action.help, command


def test_every_profile_is_offered_and_explained_and_the_default_is_the_codes():
    for command, action in _options("--profile"):
        assert tuple(action.choices) == tuple(profiles.PROFILES), command
        for name in profiles.PROFILES:
            assert re.search(rf"\b{name} \(", action.help), (command, name)  # "class (minutes ...)"
        stated = re.search(r"\(default: (\$DDP_PROFILE, else )?(\w+)\)", action.help)
        assert stated, command
        if stated.group(1):  # the environment's default, as the code resolves it
            assert stated.group(2) == profiles.DEFAULT, command
        else:
            assert stated.group(2) == action.default, command


@pytest.mark.parametrize("cuda, mps", [(False, False), (True, False), (False, True), (True, True)])
def test_the_stated_device_default_is_what_a_fit_picks(monkeypatch, cuda, mps):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: cuda)
    monkeypatch.setattr(torch.backends.mps, "is_available", lambda: mps)
    present = {"cuda": cuda, "mps": mps, "cpu": True}
    for command, action in _options("--device"):
        assert action.default is None, command
        stated = re.search(r"\(default: (.*)\)", action.help).group(1)  # "cuda when present, else ..."
        order = re.findall(r"\b(cuda|mps|cpu)\b", stated)
        assert order[-1] == "cpu", command
        expected = next(device for device in order if present[device])
        assert resolve_device(RunOptions(device=None)).type == expected, (command, stated)
