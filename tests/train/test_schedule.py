"""The per-step schedules: the learning rate's exponential decay and the 3D supervision's weight."""

from __future__ import annotations

from pathlib import Path

import pytest

from affnerf.train.config import TrainConfig
from affnerf.train.schedule import learning_rate, points_weight


def _config(**kw) -> TrainConfig:
    return TrainConfig(data=Path("."), out=Path("."), steps=200, **kw)


def test_the_learning_rate_halves_its_log_distance_at_mid_schedule():
    c = _config()
    mid = learning_rate(c, 100)
    assert mid == pytest.approx((c.optim.lr * c.optim.lr_final) ** 0.5)


def test_a_constant_points_weight_is_the_default():
    c = _config(points_weight=0.3)
    assert {points_weight(c, s) for s in (0, 57, 200, 999)} == {0.3}


@pytest.mark.parametrize(("start", "final"), [(1.0, 0.1), (0.1, 1.0)])
def test_a_scheduled_points_weight_is_a_straight_line_between_its_ends(start, final):
    c = _config(points_weight=start, points_weight_final=final)
    assert points_weight(c, 0) == pytest.approx(start) and points_weight(c, 200) == pytest.approx(final)
    assert points_weight(c, 50) == pytest.approx(0.75 * start + 0.25 * final)
    assert points_weight(c, -5) == pytest.approx(start) and points_weight(c, 400) == pytest.approx(final)
