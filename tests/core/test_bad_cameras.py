"""Bad cameras: intrinsics, poses, sizes and fields of view refused by ``Camera`` with the argument's name, and
``look_at`` refusing degenerate input instead of returning a NaN pose. The refusals use ``bad_input_harness``.
"""
from __future__ import annotations

import numpy as np
import pytest

from bad_input_harness import BAD, H, W, CaseList, camera, refusal_test
from ddp_lite.core.camera import Camera

CASES = CaseList()
case = CASES.case

# --------------------------------------------------------------------------- Camera

def _cam(K=None, pose=None, width=W, height=H):
    K = np.array([[30.0, 0, 15.5], [0, 30.0, 11.5], [0, 0, 1]]) if K is None else K
    return lambda tmp: (lambda: Camera(K, np.eye(4) if pose is None else pose, width, height))


_rot = np.eye(4)
_rot[:3, :3] = [[1, 0, 0], [0, 1, 0], [0, 0, 2]]
_nanpose = np.eye(4)
_nanpose[0, 3] = np.nan
for _id, _setup, _name in (
        ("focal 1e12", _cam(K=np.array([[1e12, 0, 15.5], [0, 1e12, 11.5], [0, 0, 1]])), "focal"),
        ("focal 1e-5", _cam(K=np.array([[1e-5, 0, 15.5], [0, 1e-5, 11.5], [0, 0, 1]])), "focal"),
        ("width True", _cam(width=True), "width"),
        ("height 0", _cam(height=0), "height"),
        ("width 2.5", _cam(width=2.5), "width"),
        ("width inf", _cam(width=float("inf")), "width"),
        ("K nan", _cam(K=np.full((3, 3), np.nan)), "K"),
        ("K last row", _cam(K=np.array([[30.0, 0, 15.5], [0, 30.0, 11.5], [0, 1, 1]])), "K"),
        ("K 2×2", _cam(K=np.eye(2)), "K"),
        ("pose not a rotation", _cam(pose=_rot), "cam_from_world"),
        ("pose nan", _cam(pose=_nanpose), "cam_from_world"),
        ("fov 180", lambda tmp: (lambda: Camera.from_fov(W, H, 180.0)), "fov_x_deg"),
        ("fov str", lambda tmp: (lambda: Camera.from_fov(W, H, "60")), "fov_x_deg")):
    case(f"Camera {_id}", BAD, _name)(_setup)


case("Camera.resized(0, 0)", BAD, "width")(lambda tmp: (lambda: camera().resized(0, 0)))


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


@pytest.mark.parametrize("args, name", [(([0, 0, 1], [0, 0, 1]), "target"), (([0, 0, 0], [0, 5, 0]), "up"),
                                        (([0, np.nan, 0], [0, 0, 1]), "eye"), (([0, 0, 0], [0, 0, np.inf]), "target"),
                                        (([0, 0, 0], [0, 0, 1], [0, 0, 0]), "up")])
def test_look_at_refuses_degenerate_input_instead_of_a_nan_pose(args, name):
    from ddp_lite.core.camera import look_at
    with pytest.raises(ValueError, match=name):
        look_at(*args)
