"""Table 3's restricted-minus-whole differences and their bootstrap intervals over objects, on hand-built objects."""

from __future__ import annotations

import numpy as np
import pytest

from affnerf.eval.grasp_intervals import (
    COMPARED,
    RESTRICTED,
    resample_within_categories,
    restriction_differences,
    restriction_intervals,
    table3_summary,
)
from affnerf.eval.grasp_table import LABELS, summarise, table3_markdown


def _cond(on: list[bool], held: list[bool]) -> dict:
    """A condition with one grasp per entry of ``on`` and ``held`` lifted grasps, each also held after the turn."""
    return {"grasps": len(on), "epsilon": [0.01] * len(on), "on_part": on, "lift": held, "disturb": held}


def _object(category: str, whole: dict, part: dict) -> dict:
    return {
        "object_id": f"{category}_{id(whole)}",
        "category": category,
        **{c: whole for c in ("true_whole", "predicted_whole")},
        **{c: part for c in RESTRICTED},
    }


def test_identical_rows_differ_by_nothing_with_no_spread():
    objects = [_object(c, _cond([True, False], [True, False]), _cond([True, False], [True, False])) for c in "ab"]
    result = restriction_intervals(objects, draws=50)
    for cond in RESTRICTED:
        for key in COMPARED:
            cell = result["rows"][cond][key]
            assert cell == {"difference": 0.0, "low": 0.0, "high": 0.0, "draws": 50}


def test_a_restriction_that_always_holds_against_a_surface_that_never_does():
    objects = [_object("pen", _cond([False] * 4, [False] * 2), _cond([True] * 4, [True] * 2)) for _ in range(5)]
    cell = restriction_intervals(objects, draws=100)["rows"]["predicted_part"]["disturb_success"]
    assert cell["difference"] == cell["low"] == cell["high"] == pytest.approx(1.0)


def test_resampling_keeps_each_category_and_its_size():
    objects = [_object("pen", _cond([True], [True]), _cond([True], [True])) for _ in range(3)]
    objects += [_object("bottle", _cond([False], [False]), _cond([False], [False])) for _ in range(5)]
    rng = np.random.default_rng(0)
    for _ in range(20):
        draw = resample_within_categories(objects, rng)
        assert sorted(o["category"] for o in draw) == ["bottle"] * 5 + ["pen"] * 3
        assert all(o in objects for o in draw)
    assert len({o["object_id"] for o in resample_within_categories(objects, np.random.default_rng(1))}) < 8


def test_mixed_objects_give_an_interval_around_the_difference_and_the_same_draws_the_same_interval():
    rng = np.random.default_rng(3)
    objects = []
    for category in ("pen", "scissors", "bottle"):
        for _ in range(5):
            whole, part = rng.random(5) < 0.5, rng.random(5) < 0.6
            objects.append(_object(category, _cond(list(whole), list(whole)), _cond(list(part), list(part))))
    result = restriction_intervals(objects, draws=300, seed=7)
    point = restriction_differences(summarise(objects))
    for cond in RESTRICTED:
        for key in COMPARED:
            cell = result["rows"][cond][key]
            assert cell["difference"] == pytest.approx(point[cond][key])
            assert cell["low"] < cell["difference"] < cell["high"] and cell["high"] - cell["low"] < 0.6
    assert restriction_intervals(objects, draws=300, seed=7) == result


def test_an_undefined_difference_has_no_interval():
    # no restricted grasp anywhere: its shares are undefined, so are the differences
    objects = [_object("pen", _cond([True], [True]), _cond([], [])) for _ in range(3)]
    cell = restriction_intervals(objects, draws=20)["rows"]["predicted_part"]["on_part_share"]
    assert cell == {"difference": None, "low": None, "high": None, "draws": 0}


def test_table3_shows_the_differences_in_points_with_their_interval():
    objects = [_object("pen", _cond([False] * 4, [False] * 2), _cond([True] * 4, [True] * 2)) for _ in range(5)]
    table = table3_markdown(table3_summary(objects), {"split": "test"})
    assert "**Restricted minus whole surface of the same mesh**" in table and "95 % bootstrap interval" in table
    assert f"| {LABELS['predicted_part']} | +100 [+100, +100] | +100 [+100, +100] | +100 [+100, +100] |" in table
    assert "Restricted minus" not in table3_markdown(summarise(objects), {"split": "test"})
