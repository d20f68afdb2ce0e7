"""What the notebooks run live at each profile: the smallest set their cells need at ``ci``, and ``class``
as the notebooks have always run it; a notebook's fits at ``ci`` cut short (``Profile.notebook_settings``)."""
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


def test_a_profiles_run_cut_short_keeps_only_the_decays_it_reaches():
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.profiles import get_profile

    ci = get_profile("ci")  # lr × 0.3 at iterations 90 and 128 of 150
    assert ci.cut_short(None) == {}
    assert ci.cut_short(50) == {"iterations": 50, "lr_milestones": ()}
    assert ci.cut_short(100) == {"iterations": 100, "lr_milestones": (90,)}
    config = FitConfig.for_profile("ci", variant="rgbd", **ci.cut_short(100))
    assert (config.paper.iterations, config.paper.lr_milestones, config.paper.lr) == (100, (90,), 1e-2)


@pytest.mark.parametrize("bad, error", [(0, ValueError), (-50, ValueError), (50.0, TypeError), (True, TypeError),
                                        ("50", TypeError)])
def test_cut_short_refuses_what_is_not_a_positive_count(bad, error):
    from ddp_lite.method.profiles import get_profile

    with pytest.raises(error, match="iterations"):
        get_profile("ci").cut_short(bad)


def test_a_notebooks_fits_run_a_third_of_cis_iterations_at_ci_and_the_profiles_own_elsewhere():
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.profiles import get_profile

    assert get_profile("ci").notebook_settings() == {"iterations": 50, "lr_milestones": ()}  # before the decay at 90
    assert get_profile("class").notebook_settings() == {} and get_profile("paper").notebook_settings() == {}
    assert FitConfig.for_profile("ci", variant="rgbd").paper.iterations == 150  # everything else: ci's own run


def test_run_variants_and_run_cases_pass_the_live_budget_and_a_callers_own_iterations_win(monkeypatch):
    from ddp_lite.evaluation import experiments

    seen = []
    monkeypatch.setattr(experiments, "run_jobs", lambda jobs, profile, options: seen.extend(jobs) or [None] * len(jobs))
    case = object()  # never read: the jobs are only recorded
    experiments.run_variants(case, ("d", "rgbd"), "ci")
    experiments.run_cases([case], "rgbd", "ci", gammas=(0.5, 0.5))
    experiments.run_variants(case, ("rgbd",), "ci", iterations=8, lr_milestones=())
    experiments.run_cases([case], "rgbd", "class")
    assert [job[3] for job in seen] == [{"iterations": 50, "lr_milestones": ()}] * 2 + [
        {"iterations": 50, "lr_milestones": (), "gammas": (0.5, 0.5)}, {"iterations": 8, "lr_milestones": ()}, {}]
