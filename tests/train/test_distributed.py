"""The same command under torchrun: two CPU processes (gloo) keep identical replicas and learn."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import replace

import pytest
from support import train_argv


@pytest.mark.parametrize("points", [False, True], ids=["paper-loss", "with-points"])
def test_two_processes_keep_identical_replicas_and_reduce_the_loss(tiny_train_config, tmp_path, points):
    config = tiny_train_config(steps=24, checkpoint_every=12)
    run = replace(config, objects_per_step=1, log_every=1, val_every=0)
    args = [
        sys.executable,
        "-m",
        "torch.distributed.run",
        "--nproc_per_node",
        "2",
        "--standalone",
        "-m",
        "affnerf.cli.main",
        *train_argv(run),
        *(["--points-weight", "0.5", "--points-per-object", "128"] if points else []),
    ]
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = subprocess.run(args, capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    summary = json.loads((config.out / "summary.json").read_text())
    assert summary["step"] == 24
    assert len(summary["replica_checksums"]) == 2 and summary["replicas_identical"]
    rows = [json.loads(line) for line in (config.out / "metrics.jsonl").read_text().splitlines()]
    if points:  # the ranks draw other objects and points: identical replicas mean their gradients were averaged
        assert all(math.isfinite(r["loss/occupancy"]) and math.isfinite(r["loss/point_affordance"]) for r in rows)
    else:
        first = sum(r["loss/total"] for r in rows[:4]) / 4
        last = sum(r["loss/total"] for r in rows[-4:]) / 4
        assert last < 0.8 * first, (first, last)
    # only rank 0 wrote: one metrics line per step, checkpoints once
    assert [r["step"] for r in rows] == list(range(1, 25))
    assert sorted(p.name for p in (config.out / "checkpoints").iterdir()) == ["step_00000012.pt", "step_00000024.pt"]
