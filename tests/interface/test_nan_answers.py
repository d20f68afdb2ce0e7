"""A NaN never passes an exercise check: a student's function that returns NaN or inf FAILs with a message saying
the result is not finite (one finite-result rule in the checks), and a NaN where the reference has one is right."""
from __future__ import annotations

import numpy as np


def test_a_student_function_returning_nan_never_passes_a_check(capsys):
    from ddp_lite.interface import exercises
    assert exercises.check_warp(lambda image, depth, ref, nbr: np.full((24, 32, 3), np.nan)) is False
    assert "finite" in capsys.readouterr().out
    assert exercises.check_fscore(lambda p, r: float("nan")) is False
    assert exercises.check_psnr(lambda a, b: np.inf) is False
    assert exercises.check_paired_change(lambda before, after: (np.nan, np.nan, np.nan)) is False
    assert "finite" in capsys.readouterr().out


def test_a_nan_where_the_reference_is_nan_is_still_right(capsys):
    from ddp_lite.interface import exercises
    from ddp_lite.interface.exercises import _not_finite
    assert _not_finite(np.array([np.nan, 1.0]), np.array([np.nan, 2.0])) is None
    assert "finite" in _not_finite(np.array([np.nan, 1.0]), np.array([1.0, 2.0]))
    assert exercises.check_fscore(lambda p, r: 0.0 if p + r == 0 else 2 * p * r / (p + r)) is True
