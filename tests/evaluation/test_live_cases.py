"""What the notebooks run live at each profile: the smallest set their cells need at ``ci``, and ``class``
as the notebooks have always run it."""
import pytest

from ddp_lite.evaluation.experiments import ablation_cases


def test_ablation_cases_ci_and_class_run_the_first_scene_and_seed_only():
    # notebook 05's cells need one case (its figure draws the first scene's first case)
    assert ablation_cases(("house", "desk"), "ci") == [("house", 0)]
    assert ablation_cases(("house", "desk"), "class") == [("house", 0)]


def test_ablation_cases_paper_runs_every_scene_and_seed():
    assert ablation_cases(["house", "desk"], "paper") == [("house", 0), ("house", 1), ("house", 2),
                                                         ("desk", 0), ("desk", 1), ("desk", 2)]


@pytest.mark.parametrize("scenes, error", [("house", TypeError), ((), ValueError), (("house", 3), ValueError)])
def test_ablation_cases_bad_scenes(scenes, error):
    with pytest.raises(error, match="scenes"):
        ablation_cases(scenes, "ci")
