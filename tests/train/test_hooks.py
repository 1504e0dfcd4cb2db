"""The after-iteration hooks: when each acts, what logging writes, and how the run's scalars evolve."""

from __future__ import annotations

import io
import json

import torch
from tqdm import tqdm

from affnerf.train import distributed as dist_utils
from affnerf.train.config import TrainConfig
from affnerf.train.hooks import AdvanceProgress, LogScalars, SaveCheckpoints, due
from affnerf.train.logger import MetricsLogger

ALONE = dist_utils.Context(rank=0, world=1, device=torch.device("cpu"))


def _outputs(loss: float, mse: float) -> dict[str, torch.Tensor | float]:
    return {
        "loss/total": torch.tensor(loss),
        "loss/mse": torch.tensor(mse),
        "loss/affordance_ce": torch.tensor(2.0),
        "train/affordance_accuracy": torch.tensor(0.5),
        "train/lr": 1e-3,
    }


def test_due_every_and_at_the_last_step():
    assert [s for s in range(1, 11) if due(s, 4, 10)] == [4, 8, 10]
    assert [s for s in range(1, 4) if due(s, 1, 3)] == [1, 2, 3]


def test_checkpoints_every_at_the_end_and_when_out_of_time():
    saved: list[int] = []
    hook = SaveCheckpoints(every=4, end=10, save=saved.append)
    for step in range(1, 11):
        hook(step=step, outputs={}, scalars={}, out_of_time=step == 6)
    assert saved == [4, 6, 8, 10]


def test_every_zero_acts_only_at_the_end_and_when_out_of_time():
    assert [s for s in range(1, 11) if due(s, 0, 10)] == [10]
    saved: list[int] = []
    hook = SaveCheckpoints(every=0, end=10, save=saved.append)
    for step in range(1, 11):
        hook(step=step, outputs={}, scalars={}, out_of_time=step == 6)
    assert saved == [6, 10]


def test_a_negative_interval_is_refused_with_one_line(tmp_path, capsys):
    from affnerf.cli.main import main

    argv = ["train", "--data", str(tmp_path), "--out", str(tmp_path / "run"), "--steps", "10"]
    for option in ("--checkpoint-every", "--log-every", "--val-every"):
        assert main([*argv, option, "-5"]) == 2
        assert f"{option} is a number of steps (>= 0; 0 = only at the end), not -5" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def test_log_scalars_writes_lines_and_replaces_the_run_scalars(tmp_path):
    config = TrainConfig(data=tmp_path, out=tmp_path, steps=3, log_every=2, rays_per_step=10)
    logger = MetricsLogger(tmp_path, enabled=True)
    bar = tqdm(total=3, file=io.StringIO())
    hooks = [LogScalars(config, ALONE, logger, bar, started=0.0), AdvanceProgress(bar)]
    scalars: dict[str, float] = {"val/psnr": 20.0}
    for step, mse in ((1, 0.1), (2, 0.01), (3, 0.001)):
        for hook in hooks:
            hook(step=step, outputs=_outputs(1.0 / step, mse), scalars=scalars, out_of_time=False)
        if step == 2:
            assert "val/psnr" not in scalars and abs(scalars["train/psnr"] - 20.0) < 1e-4
    logger.close()
    rows = [json.loads(line) for line in (tmp_path / "metrics.jsonl").read_text().splitlines()]
    assert [r["step"] for r in rows] == [2, 3]
    assert list(rows[0]) == [
        "step",
        "loss/total",
        "loss/mse",
        "loss/affordance_ce",
        "train/psnr",
        "train/affordance_accuracy",
        "train/lr",
        "perf/rays_per_second",
        "time/seconds",
    ]
    assert abs(rows[1]["loss/total"] - 1 / 3) < 1e-6 and abs(scalars["train/psnr"] - 30.0) < 1e-3
    assert rows[0]["train/lr"] == 1e-3 and bar.n == 3
    assert (tmp_path / "tb").is_dir()


def test_disabled_logger_writes_nothing(tmp_path):
    logger = MetricsLogger(tmp_path / "run", enabled=False)
    logger.scalars(1, {"loss/total": 1.0})
    logger.close()
    assert not (tmp_path / "run").exists()
