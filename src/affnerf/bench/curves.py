"""Quality against training time, compared fairly on a noisy machine.

Each configuration's time per step is measured alone first (median of steps after a warm-up); a time budget is
then turned into a number of steps, and training runs in chunks of steps (``stop_at`` + ``--resume``, the real
CLI path). After each chunk the newest checkpoint is scored on held-out objects. Wall-clock noise during the
long runs therefore changes nothing but how long the benchmark takes.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import torch

from affnerf.bench.training import training_step
from affnerf.data.dataset import Dataset
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, evaluate
from affnerf.predict.loading import load_model
from affnerf.train.cache import ObjectFrames
from affnerf.train.config import TrainConfig, config_to_json
from affnerf.train.trainer import train

#: Held-out scoring during curves: one input view, four targets at a quarter of the dataset's resolution.
CURVE_PROTOCOL = ProtocolConfig(input_views=1, target_views=4, scale=0.25, seed=0)


def step_seconds(config: TrainConfig, frames: list[ObjectFrames], steps: int = 40, warmup: int = 10) -> float:
    """Median seconds of a training step of ``config`` (sampling, forward, backward, optimiser), measured alone."""
    step, _ = training_step(config, frames, torch.device("cpu"))
    times = []
    for i in range(warmup + steps):
        start = time.perf_counter()
        step()
        if i >= warmup:
            times.append(time.perf_counter() - start)
    return statistics.median(times)


def score_run(run: Path, data: Path, split: str = "val", protocol: ProtocolConfig = CURVE_PROTOCOL) -> dict[str, Any]:
    """Mean metrics (conventions §5) of a run's newest checkpoint on a split."""
    ds = Dataset.open(data)
    objects = [ds.load_object(e) for e in ds.objects(split=split)]
    method = ConditionedNeRFMethod(load_model(run))
    return evaluate(method, objects, protocol, split, len(ds.affordance_classes)).to_json()["mean"]


def measure_curve(config: TrainConfig, minutes: float, chunks: int, seconds_per_step: float) -> dict[str, Any]:
    """Train ``config`` for ``minutes`` of its (alone-measured) step time in ``chunks``, scoring after each."""
    steps = int(minutes * 60 / seconds_per_step)
    config = replace(config, steps=steps, val_every=0, progress=False)
    curve = []
    for chunk in range(1, chunks + 1):
        stop = round(steps * chunk / chunks)
        summary = train(replace(config, resume=chunk > 1, stop_at=stop))
        m = score_run(config.out, config.data)
        curve.append(
            {
                "train_seconds": round(stop * seconds_per_step, 1),
                "step": summary.step,
                "loss": summary.scalars.get("loss/total"),
                "val_mIoU": m["mIoU"],
                "val_MPA": m["MPA"],
                "val_PSNR": m["PSNR"],
            }
        )
        print(f"{config.out.name} chunk {chunk}/{chunks}: {curve[-1]}", flush=True)
    return {
        "seconds_per_step": seconds_per_step,
        "steps": steps,
        "rays_per_second": config.rays_per_step / seconds_per_step,
        "config": config_to_json(config),
        "curve": curve,
    }
