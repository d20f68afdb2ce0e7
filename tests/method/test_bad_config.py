"""Bad method settings: every ``FitConfig`` field and run option refused with its name before any work, a run
option given where the method's settings go refused saying where it belongs, and the fit cache's folder
(``DDP_CACHE``) checked first. The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import dataclasses

from bad_input_harness import BAD, CaseList, depth, refusal_test, rgb, tiny, with_env
from ddp_lite.method.complete import complete_depth
from ddp_lite.method.config import FitConfig
from ddp_lite.method.runtime.options import RunOptions

CASES = CaseList()
case = CASES.case

# --------------------------------------------------------------------------- FitConfig fields

CONFIG_BAD = {
    "lr": [float("inf"), float("nan"), -1.0, 0.0, "0.01", True, None],
    "lr_gamma": [float("inf"), float("nan"), 0.0, -0.1, True],
    "iterations": [0, -5, 2.7, True, "10", float("nan")],
    "lr_milestones": [(-1,), ("a",), (1.5,), 5, (True,)],
    "gammas": [(float("nan"), 0.1), (float("inf"), 0.0), (0.6, 0.6), (0.5,), (-0.1, 0.5), "ab", (0.5, None)],
    "channels": [(), (8,), (8, 0), (8, 16.5), (8, True), "816", (8, -16)],
    "noise_channels": [0, 2.5, True, -1],
    "lambda_z": [1.5, float("nan"), -0.1], "lambda_i": [1.5, float("nan"), -0.1],
    "lambda_w": [1.5, float("nan"), -0.1],
    "reg_noise_std": [-1.0, float("inf"), float("nan")],
    "average_outputs": [1.0, -0.1, float("nan")],
    "ensemble": [0, 1.5, True],
    "smoothness": [-1.0, float("inf"), float("nan")],
    "smoothness_edge": [-1.0, float("inf")],
    "flatness": [-0.5, float("inf"), float("nan")], "flatness_reach": [-1.0, float("inf"), "4"],
    "image_input": [-1.0, float("nan"), "1"], "image_blur": [-0.5, float("inf")],
    "disparity_margin": [0.5, float("inf"), float("nan")],
    "held_out_fraction": [0.0, 0.5, float("nan")],
    "patience": [0, 2.5], "plateau_decays": [-1, 1.5], "eval_every": [0, True],
    "seed": [-1, 1.5, "0"],
    "auto_stop": ["yes", 1], "bf16": ["no", 0],
    "net": ["resnet", 3, None], "down": ["avg"], "up": ["cubic"], "pad": ["circular"],
    "schedule": ["linear", None], "net_input": ["grid", None, 2], "edge_guide": ["colour", None, 3],
}
for _field, _values in CONFIG_BAD.items():
    for _i, _value in enumerate(_values):
        def _setup(tmp, field=_field, value=_value):
            r, d = rgb(), depth()
            return lambda: complete_depth(r, d, variant="d", config=tiny(**{field: value}))
        case(f"config.{_field}={_value!r}", BAD, _field)(_setup)

# the run's options: checked at the run, each message naming its field
OPTIONS_BAD = {
    "callback_every": [-1, 0.5], "channels_last": [1], "progress": ["false"],
    "device": ["tpu", "cuda", "cuda:7", 3, "gpu"],
    "max_memory_gb": [0.0, -1.0, float("nan"), "8"],
}
for _field, _values in OPTIONS_BAD.items():
    for _i, _value in enumerate(_values):
        def _setup(tmp, field=_field, value=_value):
            r, d = rgb(), depth()
            return lambda: complete_depth(r, d, variant="d", config=tiny(), options=RunOptions(**{field: value}))
        case(f"options.{_field}={_value!r}", BAD, f"options.{_field}")(_setup)
# a run option given to the method's config: refused, saying where it goes
for _field in OPTIONS_BAD:
    case(f"FitConfig({_field}=...)", TypeError, f"options=RunOptions({_field}=")(
        lambda tmp, field=_field: (lambda: tiny(**{field: OPTIONS_BAD[field][0]})))
case("for_profile(progress=False)", TypeError, "progress")(
    lambda tmp: (lambda: FitConfig.for_profile("ci", variant="d", progress=False)))
case("config.replace(device='cpu')", TypeError, "device")(lambda tmp: (lambda: tiny().replace(device="cpu")))
case("config.run", AttributeError, "RunOptions")(lambda tmp: (lambda: tiny().run))
case("config.progress", AttributeError, "run option")(lambda tmp: (lambda: tiny().progress))


# --------------------------------------------------------------------------- a field's flat name inside its section
# FitConfig takes these fields by their section-qualified flat names (FitConfig(warp_cost=...)); the section itself
# names them without the repeat (config.warp.cost): the flat name read from, or given to, the section is refused
# with the field's name. Spelt out here, not read from the code.
QUALIFIED = {"net_input": ("net_inputs", "base", "meshgrid"), "warp_occlusion": ("warp", "occlusion", True),
             "warp_confidence": ("warp", "confidence", True), "warp_reach": ("warp", "reach", 2.0),
             "warp_cost": ("warp", "cost", "census"), "warp_texture": ("warp", "texture", True),
             "warp_combine": ("warp", "combine", "min")}
for _flat, (_section, _field, _value) in QUALIFIED.items():
    case(f"config.{_section}.{_flat}", AttributeError, f"config.{_section}.{_field}")(
        lambda tmp, section=_section, flat=_flat: (lambda: getattr(getattr(tiny(), section), flat)))
    case(f"{_section} section({_flat}=...)", TypeError, f"the field is {_field!r}")(
        lambda tmp, section=_section, flat=_flat, value=_value: (
            lambda: type(getattr(tiny(), section))(**{flat: value})))
    case(f"dataclasses.replace(config.{_section}, {_flat}=...)", TypeError, f"config.{_section}.{_field}")(
        lambda tmp, section=_section, flat=_flat, value=_value: (
            lambda: dataclasses.replace(getattr(tiny(), section), **{flat: value})))
    case(f"FitConfig({_field}=...)", TypeError, repr(_flat))(
        lambda tmp, field=_field, value=_value: (lambda: tiny(**{field: value})))


# --------------------------------------------------------------------------- seeds, attributes, budgets
case("seed 2**63", ValueError, "config.seed")(lambda tmp: (lambda: tiny(seed=2**63).validate()))
case("seed near 2**63 with an ensemble", ValueError, "config.seed")(
    lambda tmp: (lambda: tiny(seed=2**63 - 2, ensemble=3).validate()))
case("FitConfig typo'd attribute", AttributeError, "callback_every")(
    lambda tmp: (lambda: setattr(tiny(), "callbak_every", 5)))
case("iterations=10**9", ValueError, "config.iterations")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), variant="d", config=tiny(iterations=10**9))))


# --------------------------------------------------------------------------- the fit cache's folder
case("DDP_CACHE names a file", ValueError, "DDP_CACHE")(
    lambda tmp: ((tmp / "cache").write_text("x"),
                 with_env("DDP_CACHE", str(tmp / "cache"), lambda: complete_depth(rgb(), depth(), variant="d",
                                                                              config=tiny())))[1])


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)
