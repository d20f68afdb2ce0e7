"""The sentences a notebook prints about where a method stands come from the numbers given."""
import pytest

from ddp_lite.evaluation.standing import leads_and_trails, ordinal, standing


def test_ordinals():
    assert [ordinal(n) for n in (1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 101)] == [
        "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "23rd", "101st"]


def test_standing_names_the_rank_and_the_nearest_rival():
    errors = {"telea": 1.282, "DDP paper": 1.287, "linear": 1.0, "nearest": 2.0}
    assert standing(errors, "DDP paper", " px") == "DDP paper ranks 3rd of 4 (1.287 px), behind telea (1.282 px)"
    assert standing(errors, "linear", digits=1) == "linear ranks 1st of 4 (1.0), ahead of telea (1.3)"
    with pytest.raises(ValueError, match="name"):
        standing(errors, "DDP kit")
    with pytest.raises(ValueError, match="two methods"):
        standing({"DDP": 1.0}, "DDP")


def test_leads_and_trails_counts_the_cases_where_nothing_is_lower():
    table = {"a": {"DDP": 1.0, "x": 2.0}, "b": {"DDP": 3.0, "x": 2.0}, "c": {"DDP": 2.0, "x": 2.0}}
    assert leads_and_trails(table, "DDP") == (["a"], ["b", "c"])
