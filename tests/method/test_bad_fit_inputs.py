"""Bad inputs to a fit: ``complete_depth``'s arrays, camera, neighbours, transform and callback, the coarse-to-fine
and single-image fits, and ``merge``, each refused with its argument's name before any work; what is odd but
right is accepted; a diverged fit raises instead of returning NaN. The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import torch

from bad_input_harness import BAD, H, W, CaseList, camera, depth, refusal_test, rgb, tiny, watch
from ddp_lite.core.camera import Camera, look_at
from ddp_lite.core.views import View
from ddp_lite.data.fileio import read_pfm
from ddp_lite.method.coarse_to_fine import complete_depth_coarse_to_fine
from ddp_lite.method.complete import complete_depth
from ddp_lite.method.config import FitConfig
from ddp_lite.method.dip import fit_image
from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.method.result import merge
from ddp_lite.method.runtime.options import RunOptions

PFM_BODY = np.ones(4, "<f4").tobytes()

CASES = CaseList()
case = CASES.case

# --------------------------------------------------------------------------- complete_depth's inputs

def _fit(**kw):
    def setup(tmp):
        args = dict(rgb=rgb(), depth=depth(), variant="rgbd", config=tiny())
        args.update({k: (v() if callable(v) and not isinstance(v, type) else v) for k, v in kw.items()})
        return lambda: complete_depth(**args)
    return setup


def _holes(fraction_valid):
    d = np.full((H, W), np.nan, np.float32)
    d.flat[:fraction_valid] = 2.0
    return d


FIT_BAD = {
    "depth int": (dict(depth=lambda: np.ones((H, W), np.int32)), "depth"),
    "depth 3-D": (dict(depth=lambda: np.ones((H, W, 1), np.float32)), "depth"),
    "depth inf": (dict(depth=lambda: np.where(depth() > 0, np.inf, np.nan).astype(np.float32)), "depth"),
    "depth negative": (dict(depth=lambda: -depth()), "depth"),
    "depth all NaN": (dict(depth=lambda: _holes(0)), "depth"),
    "depth 10 valid": (dict(depth=lambda: _holes(10)), "depth"),
    "depth torch": (dict(depth=lambda: torch.ones(H, W)), "depth"),
    "depth bool": (dict(depth=lambda: np.ones((H, W), bool)), "depth"),
    "rgb (H, W)": (dict(rgb=lambda: np.zeros((H, W), np.float32)), "rgb"),
    "rgb other size": (dict(rgb=lambda: rgb(H + 2, W)), "rgb"),
    "rgb > 1": (dict(rgb=lambda: rgb() * 255), "rgb"),
    "rgb NaN": (dict(rgb=lambda: np.full((H, W, 3), np.nan, np.float32)), "rgb"),
    "rgb int64": (dict(rgb=lambda: np.zeros((H, W, 3), np.int64)), "rgb"),
    "rgb torch": (dict(rgb=lambda: torch.zeros(H, W, 3)), "rgb"),
    "rgb None for rgbd": (dict(rgb=None), "rgb"),
    "variant x": (dict(variant="x"), "variant"),
    "variant None": (dict(variant=None), "variant"),
    "config dict": (dict(config={"lr": 1e-2}), "config"),
    "config str": (dict(config="ci"), "config"),
    "options dict": (dict(options={"progress": False}), "options"),
    "options a FitConfig": (dict(options=lambda: tiny()), "options"),
    "camera array": (dict(camera=lambda: np.eye(3)), "camera"),
    "camera other size": (dict(camera=lambda: camera(h=H * 2, w=W * 2)), "camera"),
    "warp without neighbours": (dict(variant="rgbd+warp", camera=lambda: camera()), "neighbor"),
    "warp without camera": (dict(variant="rgbd+warp", neighbors=lambda: [(rgb(), camera())]), "camera"),
    "neighbour bare array": (dict(variant="rgbd+warp", camera=lambda: camera(), neighbors=lambda: [rgb()]),
                             "neighbors[0]"),
    "neighbours one View": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                 neighbors=lambda: View(rgb(), depth(), camera(), "n")), "neighbors"),
    "neighbour 1-tuple": (dict(variant="rgbd+warp", camera=lambda: camera(), neighbors=lambda: [(rgb(),)]),
                          "neighbors[0]"),
    "neighbour K for camera": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                    neighbors=lambda: [(rgb(), np.eye(3))]), "neighbors[0]"),
    "neighbour rgb size": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                neighbors=lambda: [(rgb(H + 1, W), camera())]), "neighbors[0]"),
    "neighbour faces away": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                  neighbors=lambda: [(rgb(), camera(look_at((0, 0, 0), (0, 0, -1))))]), "neighbo"),
    "neighbour 1e6 m away": (dict(variant="rgbd+warp", camera=lambda: camera(),
                                  neighbors=lambda: [(rgb(), camera(look_at((1e6, 0, 0), (1e6, 0, 1))))]), "neighbo"),
    "gt_depth shape": (dict(gt_depth=lambda: np.ones((H, W + 1), np.float32)), "gt_depth"),
    "transform str": (dict(transform="auto"), "transform"),
    "init str": (dict(init="last"), "init"),
    "3000×4000 at ci": (dict(rgb=None, variant="d", depth=lambda: np.full((3000, 4000), 2.0, np.float32),
                             config=lambda: FitConfig.for_profile("ci", variant="d")), "max_memory_gb"),
    "max_memory_gb too small": (dict(options=lambda: RunOptions(max_memory_gb=0.01)), "max_memory_gb"),
}
for _id, (_kw, _name) in FIT_BAD.items():
    case(f"complete_depth {_id}", BAD, _name)(_fit(**_kw))


def _c2f(**kw):
    def setup(tmp):
        r, d = rgb(), depth()
        return lambda: complete_depth_coarse_to_fine(r, d, variant="rgbd", config=tiny(), **kw)
    return setup


for _kw, _name in ((dict(scale=1), "scale"), (dict(scale=2.0), "scale"), (dict(coarse_fraction=1.0), "coarse_fraction"),
                   (dict(coarse_fraction=float("nan")), "coarse_fraction")):
    case(f"coarse_to_fine {_kw}", BAD, _name)(_c2f(**_kw))


def _dip(**kw):
    def setup(tmp):
        args = dict(image=rgb(), config=tiny())
        args.update({k: (v() if callable(v) else v) for k, v in kw.items()})
        return lambda: fit_image(**args)
    return setup


for _id, _kw, _name in (("mask uint8", dict(mask=lambda: np.ones((H, W), np.uint8)), "mask"),
                        ("mask 3 known", dict(mask=lambda: np.arange(H * W).reshape(H, W) < 3), "mask"),
                        ("image (H, W)", dict(image=lambda: np.zeros((H, W), np.float32)), "image"),
                        ("clean size", dict(clean=lambda: rgb(H + 1, W)), "clean"),
                        ("config lr nan", dict(config=lambda: tiny(lr=float("nan"))), "lr")):
    case(f"fit_image {_id}", BAD, _name)(_dip(**_kw))

case("merge shapes", BAD, "input_depth")(lambda tmp: (lambda: merge(depth(), depth(H + 1, W))))


# --------------------------------------------------------------------------- found while hardening
case("complete_depth callback=5", TypeError, "callback")(_fit(callback=5))
case("DisparityTransform.from_depth margin 0", BAD, "margin")(
    lambda tmp: (lambda: DisparityTransform.from_depth(depth(), margin=0.0)))


# --------------------------------------------------------------------------- transforms
case("transform narrower than the valid depth", ValueError, "transform")(
    lambda tmp: (lambda: complete_depth(rgb(), watch(np.linspace(1.0, 3.0, H * W, dtype=np.float32).reshape(H, W)),
                                        variant="d", config=tiny(), transform=DisparityTransform(1.0, 2.0))))


# --------------------------------------------------------------------------- scale and range
case("depth 1e-30 m beside 2 m", ValueError, "depth")(
    lambda tmp: (lambda: complete_depth(rgb(), watch(np.where(np.eye(H, W, dtype=bool), 1e-30, 2.0).astype(np.float32)),
                                        variant="d", config=tiny())))
case("float64 depth beyond float32", ValueError, "depth")(
    lambda tmp: (lambda: complete_depth(rgb(), watch(np.where(np.eye(H, W, dtype=bool), 1e300, 2.0)),
                                        variant="d", config=tiny())))


# --------------------------------------------------------------------------- neighbours that add nothing

def _neighbour(pose):
    return (rgb(), camera(pose))


_SIDE = look_at((0.2, 0.0, 0.0), (0.0, 0.0, 2.0))
_K_640x480 = np.array([[525.0, 0.0, 319.5], [0.0, 525.0, 239.5], [0.0, 0.0, 1.0]])  # TUM fr1's K, for 640×480
case("intrinsics for 640×480 on a 32×24 image", ValueError, "K: the principal point")(  # refused by Camera itself
    lambda tmp: (lambda: complete_depth(rgb(), depth(), Camera(_K_640x480, np.eye(4), W, H), variant="rgbd",
                                        config=tiny())))
case("a neighbour's intrinsics for 640×480 on a 32×24 image", ValueError, "K: the principal point")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), camera(), [(rgb(), Camera(_K_640x480, _SIDE, W, H))],
                                        config=tiny())))
case("neighbour at the reference's pose", ValueError, "neighbors[0]")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), camera(np.eye(4)), [_neighbour(np.eye(4))], config=tiny())))
case("the same neighbour twice", ValueError, "neighbors[1]")(
    lambda tmp: (lambda n: (lambda: complete_depth(rgb(), depth(), camera(look_at((0, 0, 0), (0, 0, 2))), [n, n],
                                                   config=tiny())))(_neighbour(_SIDE)))


# --------------------------------------------------------------------------- conventions
case("gt_depth with 0 for unknown", ValueError, "gt_depth")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), variant="d", config=tiny(),
                                        gt_depth=watch(np.where(np.isnan(depth()), 0.0, 2.0).astype(np.float32)))))
case("merge() with 0 for holes", ValueError, "input_depth")(
    lambda tmp: (lambda: merge(watch(np.nan_to_num(depth(), nan=0.0)), depth())))
case("merge() with a string for ddp_depth", TypeError, "ddp_depth")(
    lambda tmp: (lambda: merge(depth(), "filled.npy")))
case("neighbors=None for rgbd+warp", ValueError, "neighbor")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), camera(), None, config=tiny())))
case("callback with callback_every=0", ValueError, "callback_every")(
    lambda tmp: (lambda: complete_depth(rgb(), depth(), variant="d", config=tiny(), callback=lambda *a: None)))
case("fit_image callback with callback_every=0", ValueError, "callback_every")(
    lambda tmp: (lambda: fit_image(rgb(), config=tiny(), callback=lambda *a: None)))


# --------------------------------------------------------------------------- sizes the net cannot take

for _shape in ((1, 40), (4, 4), (8, 8)):
    case(f"depth {_shape[0]}×{_shape[1]} for the ci net", ValueError, "at least")(
        lambda tmp, s=_shape: (lambda: complete_depth(rgb(*s), watch(np.full(s, 2.0, np.float32)), variant="d",
                                                      config=FitConfig.for_profile("ci", variant="d", iterations=1))))
case("fit_image 8×8 for the ci net", ValueError, "at least")(
    lambda tmp: (lambda: fit_image(rgb(8, 8), config=FitConfig.for_profile("ci", variant="rgbd", iterations=1))))


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


# --------------------------------------------------------------------------- accepted on purpose

def test_accepted_on_purpose(tmp_path):
    """Inputs that look odd but are right, and must keep working."""
    # PFM with CRLF line ends and a comment line (both occur in the wild)
    (tmp_path / "crlf.pfm").write_bytes(b"Pf\r\n2 2\r\n-1.0\r\n" + PFM_BODY)
    (tmp_path / "comment.pfm").write_bytes(b"Pf\n# made by hand\n2 2\n-1.0\n" + PFM_BODY)
    for name in ("crlf.pfm", "comment.pfm"):
        np.testing.assert_array_equal(read_pfm(tmp_path / name), np.ones((2, 2), np.float32))
    # an integral float size (from arithmetic) is a size
    assert Camera(np.array([[30.0, 0, 15.5], [0, 30.0, 11.5], [0, 0, 1]]), np.eye(4), 32.0, 24.0).width == 32
    # learning-rate growth (lr_gamma > 1) is a lever, not a mistake; NumPy integers are integers
    tiny(lr_gamma=2.0, iterations=np.int64(2), lr_milestones=(np.int32(1),)).validate()
    # KITTI's testing split has no ground truth: all-NaN depth is the truth there
    # one blind neighbour among seeing ones: a warning, the fit goes on
    from ddp_lite.method.input_checks import check_fit_inputs
    away = camera(look_at((0, 0, 0), (0, 0, -1)))
    with pytest.warns(UserWarning, match=r"neighbors\[1\]"):
        check_fit_inputs(rgb(), depth(), camera(), [(rgb(), camera(look_at((0.1, 0, 0), (0.1, 0, 1)))), (rgb(), away)],
                          "rgbd+warp", tiny(), None, None)


# --------------------------------------------------------------------------- after a fit has run

def test_non_finite_output_raises(monkeypatch):
    """A diverged fit raises; it never returns NaN that merged() would hide among the valid pixels."""
    import ddp_lite.method.loop as loop

    real_run = loop.run

    def diverging(*args, **kwargs):
        output, *rest = real_run(*args, **kwargs)
        return (torch.full_like(output, float("nan")), *rest)
    monkeypatch.setattr(loop, "run", diverging)
    with pytest.raises(FloatingPointError, match="lr"):
        complete_depth(rgb(), depth(), variant="d", config=tiny(iterations=1))
    with pytest.raises(FloatingPointError, match="lr"):
        fit_image(rgb(), config=tiny(iterations=1))


def test_neighbour_without_parallax_is_warned():
    """Depth in millimetres with poses in metres: 2000 "m" away, a 0.2 m baseline shifts < 0.5 px."""
    from ddp_lite.method.input_checks import check_fit_inputs
    ref = camera(look_at((0, 0, 0), (0, 0, 2)))
    millimetres = depth() * 1000.0
    with pytest.warns(UserWarning, match=r"neighbors\[0\].*px of parallax.*same unit"):
        check_fit_inputs(rgb(), millimetres, ref, [_neighbour(_SIDE)], "rgbd+warp", tiny(), None, None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the same views in metres: parallax of pixels, no warning
        check_fit_inputs(rgb(), depth(), ref, [_neighbour(_SIDE)], "rgbd+warp", tiny(), None, None)


def test_conventions_that_are_accepted():
    """NumPy integer seeds are seeds; neighbors=None means none; a field changes by a copy, read by its section."""
    config = tiny(seed=np.int64(3))
    assert type(config.paper.seed) is int
    a = complete_depth(rgb(), depth(), variant="d", config=config, neighbors=None)
    b = complete_depth(rgb(), depth(), variant="d", config=tiny(seed=3))
    np.testing.assert_array_equal(a.depth, b.depth)
    assert config.replace(lr=1e-2).paper.lr == 1e-2
    with pytest.raises(AttributeError, match=r"config\.replace\(lr="):
        config.lr = 1e-2
    with pytest.raises(AttributeError, match=r"config\.paper\.lr"):
        config.lr
    # the smallest size the ci net takes runs: the SSIM window (11) beats its down-sampling factor + 1 (9)
    ci = FitConfig.for_profile("ci", variant="d", iterations=1)
    complete_depth(rgb(11, 11), np.full((11, 11), 2.0, np.float32), variant="d", config=ci)
