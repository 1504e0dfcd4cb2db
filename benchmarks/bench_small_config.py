"""Choosing the `small` configuration by measurement: held-out affordance mIoU against training wall time.

Each candidate trains on the same small generated dataset for the same training time. So that the comparison
holds on a noisy machine, each candidate's time per step is first measured alone (median of 40 steps after a
warm-up), and the time budget is turned into a number of steps; training then runs in chunks of steps
(``stop_at`` + ``--resume``, the real CLI path), and after each chunk the newest checkpoint is scored on the
held-out `val` objects (one input view, four target views at 100x75, per-category mIoU averaged over categories,
GUIDE 5). The constant-class guess (background everywhere) is scored on the same views. Run:

    .venv/bin/python benchmarks/bench_small_config.py [--minutes 10] [--chunks 5] [--candidates A,B,C]

Writes ``benchmarks/results/small_config.json`` and prints the table.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from dataclasses import replace
from pathlib import Path

import torch

from affnerf.bench.environment import describe_machine
from affnerf.data.dataset import Dataset
from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.methods.constant import ConstantMethod
from affnerf.eval.protocol import ProtocolConfig, evaluate
from affnerf.predict.loading import load_model
from affnerf.model.factory import build_model
from affnerf.train.cache import load_frames
from affnerf.train.config import SMALL, TrainConfig, config_to_json
from affnerf.train.loss import nerf_loss
from affnerf.train.sampler import RaySampler
from affnerf.train.trainer import train

HERE = Path(__file__).parent
M = SMALL.model
CANDIDATES = {
    "A": ("field 96x4, 32+32 samples, 512 rays", replace(SMALL, rays_per_step=512, model=replace(M, field_width=96, field_depth=4, num_coarse=32, num_fine=32, color_width=48, affordance_width=48))),
    "B": ("field 64x4, 24+24 samples, 256 rays", replace(SMALL, rays_per_step=256, model=replace(M, field_width=64, field_depth=4, num_coarse=24, num_fine=24, color_width=32, affordance_width=32))),
    "C": ("field 48x3, 16+16 samples, 256 rays", replace(SMALL, rays_per_step=256, model=replace(M, field_width=48, field_depth=3, num_coarse=16, num_fine=16, color_width=32, affordance_width=32))),
    "D": ("field 64x4, 48 coarse only, 256 rays", replace(SMALL, rays_per_step=256, model=replace(M, field_width=64, field_depth=4, num_coarse=48, num_fine=0, color_width=32, affordance_width=32))),
}  # fmt: skip
PROTOCOL = ProtocolConfig(input_views=1, target_views=4, scale=0.25, seed=0)


def dataset(root: Path) -> Path:
    """The small dataset: 8 categories x 6 objects (4 train, 1 val, 1 test), 24 views of 400x300."""
    generate_dataset(GenerateConfig(out=root, objects_per_category=6, views=24, workers=2, seed=0), progress=False)
    return root


def step_seconds(config: TrainConfig, data: Path, runs: Path) -> float:
    """Median seconds per training step of a configuration, measured alone."""
    frames = [load_frames(p) for p in sorted((runs / "cache").iterdir()) if (p / "meta.json").is_file()]
    torch.manual_seed(0)
    model = build_model(config.model, 12)
    optimizer = torch.optim.Adam(model.parameters(), lr=1e-3)
    sampler = RaySampler(frames, config.objects_per_step, config.rays_per_step, config.foreground_fraction, 0)
    generator = torch.Generator().manual_seed(0)
    times = []
    for i in range(50):
        start = time.perf_counter()
        b = sampler.next_batch()
        coarse, fine = model(b.images, b.input_intrinsics, b.input_poses, b.ray_object, b.origins, b.dirs, b.background,
                             True, generator)  # fmt: skip
        loss = nerf_loss(coarse, fine, b.rgb, b.labels, config.affordance_weight).total
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        if i >= 10:
            times.append(time.perf_counter() - start)
    return statistics.median(times)


def score(run: Path, data: Path) -> dict:
    ds = Dataset.open(data)
    objects = [ds.load_object(e) for e in ds.objects(split="val")]
    result = evaluate(ConditionedNeRFMethod(load_model(run)), objects, PROTOCOL, "val", len(ds.affordance_classes))
    return result.to_json()["mean"]


def measure(name: str, data: Path, runs: Path, minutes: float, chunks: int, seconds_per_step: float) -> dict:
    label, base = CANDIDATES[name]
    steps = int(minutes * 60 / seconds_per_step)
    config = replace(base, data=data, out=runs / name, steps=steps, val_every=0, progress=False,
                     cache_dir=runs / "cache", image_scale=0.25)  # fmt: skip
    curve = []
    for chunk in range(1, chunks + 1):
        stop = round(steps * chunk / chunks)
        summary = train(replace(config, resume=chunk > 1, stop_at=stop))
        m = score(config.out, data)
        curve.append({"train_seconds": round(stop * seconds_per_step, 1), "step": summary.step,
                      "loss": summary.scalars.get("loss/total"), "val_mIoU": m["mIoU"], "val_MPA": m["MPA"],
                      "val_PSNR": m["PSNR"]})  # fmt: skip
        print(f"{name} chunk {chunk}/{chunks}: {curve[-1]}", flush=True)
    return {"label": label, "seconds_per_step": seconds_per_step, "steps": steps, "config": config_to_json(config),
            "curve": curve}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--chunks", type=int, default=5)
    parser.add_argument("--candidates", default=",".join(CANDIDATES))
    parser.add_argument("--work", type=Path, default=HERE / ".work" / "small_config")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "small_config.json")
    args = parser.parse_args()
    data = dataset(args.work / "data")
    ds = Dataset.open(data)
    objects = [ds.load_object(e) for e in ds.objects(split="val")]
    constant = evaluate(ConstantMethod(0), objects, PROTOCOL, "val", len(ds.affordance_classes)).to_json()["mean"]
    results = {"benchmark": "small_config", "machine": describe_machine(), "minutes": args.minutes,
               "protocol": PROTOCOL.__dict__, "constant_guess": constant, "candidates": {}}  # fmt: skip
    started = time.time()
    names = args.candidates.split(",")
    runs = args.work / "runs"
    # decode the training frames once (a 1-step run), then time every candidate alone before any training
    train(replace(SMALL, data=data, out=runs / "warmup", steps=1, val_every=0, progress=False, cache_dir=runs / "cache",
                  image_scale=0.25, resume=(runs / "warmup" / "checkpoints").is_dir()))  # fmt: skip
    timing = {n: step_seconds(replace(CANDIDATES[n][1], image_scale=0.25), data, runs) for n in names}
    print("seconds per step:", {n: round(t, 4) for n, t in timing.items()}, flush=True)
    for name in names:
        results["candidates"][name] = measure(name, data, runs, args.minutes, args.chunks, timing[name])
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=1) + "\n")
    print(f"constant guess: val mIoU {constant['mIoU']:.3f}")
    for name, r in results["candidates"].items():
        last = r["curve"][-1]
        print(f"{name} {r['label']}: step {last['step']}, val mIoU {last['val_mIoU']:.3f}, MPA {last['val_MPA']:.3f}")
    print(f"{time.time() - started:.0f} s -> {args.out}")


if __name__ == "__main__":
    main()
