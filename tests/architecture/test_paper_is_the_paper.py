"""``ddp_lite.method.paper`` is the paper's method alone: none of its modules imports the kit's additions
(``ddp_lite.method.kit``) or the classical methods (``ddp_lite.classical``); the kit reaches the paper's
loss only as arguments (a warp term, occlusion tests, extra terms, extra input channels)."""
from __future__ import annotations

import importlib
import pkgutil
import types

import ddp_lite.method.paper as paper
from test_import_graph import graph

FORBIDDEN = ("ddp_lite.method.kit", "ddp_lite.classical")


def paper_modules() -> list[str]:
    return [f"{paper.__name__}.{info.name}" for info in pkgutil.iter_modules(paper.__path__)]


def test_no_module_of_the_paper_imports_the_kit_or_the_classical_methods():
    names = paper_modules()
    assert {"disparity", "losses", "warp", "nets", "variants", "total_loss"} <= {n.rsplit(".", 1)[1] for n in names}
    edges = graph()
    found = [f"{name} imports {target}" for name in names for target in edges[name]
             if target.startswith(FORBIDDEN)]
    assert found == []
    for name in names:  # and nothing of them sits in a module's globals once imported
        module = importlib.import_module(name)
        for key, value in vars(module).items():
            home = value.__name__ if isinstance(value, types.ModuleType) else getattr(value, "__module__", None)
            assert not (isinstance(home, str) and home.startswith(FORBIDDEN)), f"{name}.{key} comes from {home}"


def test_the_paper_imports_nothing_else_of_the_method():
    edges = graph()
    found = [f"{name} imports {target}" for name in paper_modules() for target in edges[name]
             if target.startswith("ddp_lite.method.") and not target.startswith("ddp_lite.method.paper")]
    assert found == []
