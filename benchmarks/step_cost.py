"""What a training step of the small preset costs on one CPU thread, and where (issue 12, quality per CPU-minute).

Builds the preset's trainer on a dataset (its frame and point cache warmed beforehand, ``side_by_side.sh``'s
``warm_cache``) once per variant, then times whole training iterations (``Trainer.train_iteration``: drawing the
batch, forward, loss, backward, Adam) of every variant in turns of ``--block`` steps, so that each variant sees the
same machine noise; a step's parts (drawing, forward, backward, optimiser) are timed in a separate pass. Variants:
the optimiser unfused (a loop of small operations per parameter tensor, as before) or fused
(:func:`affnerf.train.state.make_optimizer`), and the coarse field its own or shared (``--model.coarse-field``).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/step_cost.py --data DATA --cache CACHE \\
        --out benchmarks/results/step_cost.json
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import tempfile
import time
from pathlib import Path
from typing import Any

import torch

from affnerf.environment import describe_machine
from affnerf.train import distributed as dist_utils
from affnerf.train.config import SMALL
from affnerf.train.trainer import Trainer

#: name -> (fused optimiser, coarse field)
VARIANTS = {
    "unfused Adam, own coarse field": (False, "own"),
    "fused Adam, own coarse field": (True, "own"),
    "fused Adam, shared field": (True, "shared"),
}


def make_trainer(data: Path, cache: Path, out: Path, fused: bool, coarse_field: str) -> Trainer:
    """The small preset's trainer on ``data`` (nothing logged or validated), its optimiser fused or not."""
    model = dataclasses.replace(SMALL.model, coarse_field=coarse_field)
    config = dataclasses.replace(
        SMALL, data=data, out=out, model=model, steps=10**6, val_every=0, progress=False,
        checkpoint_every=10**9, cache_dir=cache, device="cpu",
    )  # fmt: skip
    trainer = Trainer(config, dist_utils.setup("cpu"))
    trainer.setup()
    if not fused:
        trainer.state.optimizer = torch.optim.Adam(trainer.state.model.parameters(), lr=config.optim.lr)
    return trainer


def step_parts(trainer: Trainer, steps: int) -> dict[str, float]:
    """Mean milliseconds of a step's parts over ``steps`` steps: drawing rays and points, forward and loss,
    backward, optimiser."""
    state, totals = trainer.state, dict.fromkeys(["draw", "forward", "backward", "optimiser"], 0.0)
    assert state.points is not None
    for _ in range(steps):
        t0 = time.perf_counter()
        batch = state.sampler.next_batch()
        points = state.points.draw(batch.object_ids)
        t1 = time.perf_counter()
        total, _ = trainer._loss(batch, points, trainer.config.points_weight)
        t2 = time.perf_counter()
        state.optimizer.zero_grad(set_to_none=True)
        total.backward()
        t3 = time.perf_counter()
        state.optimizer.step()
        t4 = time.perf_counter()
        for key, seconds in zip(totals, (t1 - t0, t2 - t1, t3 - t2, t4 - t3), strict=True):
            totals[key] += seconds
    return {key: 1000.0 * value / steps for key, value in totals.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--cache", type=Path, required=True, help="the warmed frame and point cache")
    parser.add_argument("--blocks", type=int, default=6, help="turns per variant")
    parser.add_argument("--block", type=int, default=50, help="steps a turn")
    parser.add_argument("--warmup", type=int, default=20)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    torch.set_num_threads(1)
    work = Path(tempfile.mkdtemp(prefix="step_cost_"))
    trainers = {
        name: make_trainer(args.data, args.cache, work / str(i), fused, coarse)
        for i, (name, (fused, coarse)) in enumerate(VARIANTS.items())
    }
    seconds: dict[str, list[float]] = {name: [] for name in trainers}
    for trainer in trainers.values():
        for step in range(args.warmup):
            trainer.train_iteration(step)
    for block in range(args.blocks):
        for name, trainer in trainers.items():
            first = args.warmup + block * args.block
            t0 = time.perf_counter()
            for step in range(first, first + args.block):
                trainer.train_iteration(step)
            seconds[name].append((time.perf_counter() - t0) / args.block)
    rows: dict[str, Any] = {}
    for name, trainer in trainers.items():
        per_block = sorted(seconds[name])
        rows[name] = {
            "ms_per_step_median_block": 1000.0 * per_block[len(per_block) // 2],
            "ms_per_step_blocks": [round(1000.0 * s, 1) for s in seconds[name]],
            "parts_ms": step_parts(trainer, args.block),
            "parameters": sum(p.numel() for p in trainer.state.model.parameters()),
        }
        print(name, json.dumps(rows[name]))
    payload = {"machine": describe_machine(), "args": {k: str(v) for k, v in vars(args).items()}, "variants": rows}
    args.out.write_text(json.dumps(payload, indent=1) + "\n")


if __name__ == "__main__":
    main()
