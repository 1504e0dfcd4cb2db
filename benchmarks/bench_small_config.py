"""Choosing the `small` configuration by measurement: held-out affordance mIoU against training time.

Candidates train on the same small generated dataset for the same training time, compared as in
:mod:`affnerf.bench.curves` (step time measured alone, budgets in steps, chunks scored on the `val` objects). The
constant-class guess (background everywhere) is scored on the same views. Run:

    .venv/bin/python benchmarks/bench_small_config.py [--minutes 10] [--chunks 4] [--candidates A,B,C,D]

Writes ``benchmarks/results/small_config.json`` and prints the table.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

from affnerf.bench.curves import CURVE_PROTOCOL, measure_curve, step_seconds
from affnerf.data.dataset import Dataset
from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.environment import describe_machine
from affnerf.eval.methods.constant import ConstantMethod
from affnerf.eval.protocol import evaluate
from affnerf.train.cache import load_frames
from affnerf.train.config import SMALL
from affnerf.train.trainer import train

HERE = Path(__file__).parent
M = SMALL.model
CANDIDATES = {
    "A": (
        "field 96x4, 32+32 samples, 512 rays",
        replace(
            SMALL,
            rays_per_step=512,
            model=replace(
                M, field_width=96, field_depth=4, num_coarse=32, num_fine=32, color_width=48, affordance_width=48
            ),
        ),
    ),
    "B": (
        "field 64x4, 24+24 samples, 256 rays",
        replace(
            SMALL,
            rays_per_step=256,
            model=replace(
                M, field_width=64, field_depth=4, num_coarse=24, num_fine=24, color_width=32, affordance_width=32
            ),
        ),
    ),
    "C": (
        "field 48x3, 16+16 samples, 256 rays",
        replace(
            SMALL,
            rays_per_step=256,
            model=replace(
                M, field_width=48, field_depth=3, num_coarse=16, num_fine=16, color_width=32, affordance_width=32
            ),
        ),
    ),
    "D": (
        "field 64x4, 48 coarse only, 256 rays",
        replace(
            SMALL,
            rays_per_step=256,
            model=replace(
                M, field_width=64, field_depth=4, num_coarse=48, num_fine=0, color_width=32, affordance_width=32
            ),
        ),
    ),
}


def dataset(root: Path) -> Path:
    """The small dataset: 8 categories x 6 objects (4 train, 1 val, 1 test), 24 views of 400x300."""
    generate_dataset(GenerateConfig(out=root, objects_per_category=6, views=24, workers=2, seed=0), progress=False)
    return root


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--chunks", type=int, default=4)
    parser.add_argument("--candidates", default=",".join(CANDIDATES))
    parser.add_argument("--work", type=Path, default=HERE / ".work" / "small_config")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "small_config.json")
    args = parser.parse_args()
    data = dataset(args.work / "data")
    ds = Dataset.open(data)
    objects = [ds.load_object(e) for e in ds.objects(split="val")]
    constant = evaluate(ConstantMethod(0), objects, CURVE_PROTOCOL, "val", len(ds.affordance_classes)).to_json()["mean"]
    results = {
        "benchmark": "small_config",
        "machine": describe_machine(),
        "minutes": args.minutes,
        "protocol": CURVE_PROTOCOL.__dict__,
        "constant_guess": constant,
        "candidates": {},
    }
    started = time.time()
    names = args.candidates.split(",")
    runs = args.work / "runs"
    # decode the training frames once (a 1-step run), then time every candidate alone before any training
    train(
        replace(
            SMALL,
            data=data,
            out=runs / "warmup",
            steps=1,
            val_every=0,
            progress=False,
            cache_dir=runs / "cache",
            image_scale=0.25,
            resume=(runs / "warmup" / "checkpoints").is_dir(),
        )
    )
    frames = [load_frames(p) for p in sorted((runs / "cache").iterdir()) if (p / "meta.json").is_file()]
    timing = {n: step_seconds(replace(CANDIDATES[n][1], image_scale=0.25), frames) for n in names}
    print("seconds per step:", {n: round(t, 4) for n, t in timing.items()}, flush=True)
    for name in names:
        label, base = CANDIDATES[name]
        config = replace(base, data=data, out=runs / name, cache_dir=runs / "cache", image_scale=0.25)
        results["candidates"][name] = {"label": label, **measure_curve(config, args.minutes, args.chunks, timing[name])}
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=1) + "\n")
    print(f"constant guess: val mIoU {constant['mIoU']:.3f}")
    for name, r in results["candidates"].items():
        last = r["curve"][-1]
        print(f"{name} {r['label']}: step {last['step']}, val mIoU {last['val_mIoU']:.3f}, MPA {last['val_MPA']:.3f}")
    print(f"{time.time() - started:.0f} s -> {args.out}")


if __name__ == "__main__":
    main()
