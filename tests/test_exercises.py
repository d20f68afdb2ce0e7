"""The exercise checks pass a correct solution and fail a wrong one (with a message)."""
import numpy as np

from ddp_lite import exercises, ssim, warp_to_reference


def correct_and_wrong():
    return {
        "check_psnr": (lambda a, b: 10 * np.log10(1 / np.mean((a - b) ** 2)), lambda a, b: np.mean((a - b) ** 2)),
        "check_masked_mse": (lambda o, t, m: ((o - t) ** 2)[m].mean(), lambda o, t, m: ((o - t) ** 2).mean()),
        "check_disparity_transform": (
            lambda d, a, b, c: (1 / (np.clip(d, a, b) + c) - 1 / (b + c)) / (1 / (a + c) - 1 / (b + c)),
            lambda d, a, b, c: 1 / np.clip(d, a, b)),
        "check_hole_rmse": (lambda p, g, i: np.sqrt(np.mean((p - g)[np.isnan(i)] ** 2)),
                            lambda p, g, i: np.sqrt(np.mean((p - g) ** 2))),
        "check_ssim": (lambda x, y: ssim(x, y), lambda x, y: 1 - np.abs(x - y).mean()),
        "check_masked_l1": (lambda x, y, m: np.abs(x - y)[m].mean(), lambda x, y, m: np.abs(x - y).mean()),
        "check_backproject": (
            lambda d, K: np.stack([*np.meshgrid(np.arange(d.shape[1]), np.arange(d.shape[0])), np.ones_like(d)],
                                  axis=-1) @ np.linalg.inv(K).T * d[..., None],
            lambda d, K: np.stack([d, d, d], axis=-1)),
        "check_warp": (lambda *a: warp_to_reference(*a)[0], lambda img, d, r, n: img),
        "check_fscore": (lambda p, r: 0.0 if p + r == 0 else 2 * p * r / (p + r), lambda p, r: (p + r) / 2),
        "check_d1": (lambda p, g: 100 * np.mean(((np.abs(p - g) > 3) & (np.abs(p - g) > 0.05 * g))[np.isfinite(g)]),
                     lambda p, g: 100 * np.mean((np.abs(p - g) > 3)[np.isfinite(g)])),
    }


def test_every_check_passes_a_correct_solution_and_fails_a_wrong_one(capsys):
    pairs = correct_and_wrong()
    assert set(pairs) | {"check_nearest_fill"} == set(exercises.__all__)
    for name, (right, wrong) in pairs.items():
        check = getattr(exercises, name)
        assert check(right) is True, name
        assert check(wrong) is False, name
    out = capsys.readouterr().out
    assert out.count("PASS") == len(pairs) and out.count("FAIL") == len(pairs)


def test_nearest_fill_check_and_a_crashing_solution_is_reported_not_raised(capsys):
    from scipy import ndimage

    def nearest(depth):
        holes = np.isnan(depth)
        _, (rows, cols) = ndimage.distance_transform_edt(holes, return_indices=True)
        return depth[rows, cols]

    assert exercises.check_nearest_fill(nearest) is True
    assert exercises.check_nearest_fill(lambda d: 1 / 0) is False
    assert "ZeroDivisionError" in capsys.readouterr().out
