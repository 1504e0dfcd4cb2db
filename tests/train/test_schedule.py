"""The per-step schedules: the learning rate's exponential decay and the 3D supervision's weight."""

from __future__ import annotations

from dataclasses import replace
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


def _optim_config(**kw) -> TrainConfig:
    c = _config()
    return replace(c, optim=replace(c.optim, lr=1e-3, lr_final=1e-5, **kw))


def test_a_warm_up_rises_linearly_to_the_peak_then_the_decay_takes_the_remaining_steps():
    c = _optim_config(warmup_steps=20)
    assert learning_rate(c, 0) == pytest.approx(5e-5) and learning_rate(c, 9) == pytest.approx(5e-4)
    assert learning_rate(c, 20) == pytest.approx(1e-3) and learning_rate(c, 200) == pytest.approx(1e-5)
    assert learning_rate(c, 110) == pytest.approx((1e-3 * 1e-5) ** 0.5)  # the middle of the 180 decay steps


def test_a_cosine_decay_stays_higher_than_the_exponential_one_between_its_ends():
    cosine, exponential = _optim_config(schedule="cosine"), _optim_config()
    assert learning_rate(cosine, 0) == pytest.approx(1e-3) and learning_rate(cosine, 200) == pytest.approx(1e-5)
    assert learning_rate(cosine, 100) == pytest.approx(0.5 * (1e-3 + 1e-5))
    rates = [learning_rate(cosine, s) for s in range(201)]
    assert all(a >= b for a, b in zip(rates, rates[1:], strict=False))
    assert all(learning_rate(cosine, s) > learning_rate(exponential, s) for s in range(1, 180))


def test_a_warm_up_takes_at_most_a_tenth_of_a_short_run():
    c = _optim_config(warmup_steps=300)  # 200 steps: 20 of warm-up
    assert learning_rate(c, 9) == pytest.approx(5e-4) and learning_rate(c, 20) == pytest.approx(1e-3)


def test_a_negative_warm_up_is_refused_with_one_line(tmp_path, capsys):
    from affnerf.cli.main import main

    argv = ["train", "--data", str(tmp_path), "--out", str(tmp_path / "run"), "--steps", "10"]
    assert main([*argv, "--optim.warmup-steps", "-1"]) == 2
    assert "--optim.warmup-steps is a number of steps (>= 0), not -1" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
