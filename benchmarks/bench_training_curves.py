"""Training speed at equal quality: the fast path against the reference path, side by side.

The reference is vanilla NeRF sampling: uniform coarse samples over the whole [0.1, 1.5] m range, then fine
samples, every ray evaluated. The fast path is the `small` configuration: samples only where rays cross the
canonical cube (rays that miss it are not evaluated). The reference gets twice the fast path's samples, so that
its samples still land about as densely on the object. Both train the same architecture on the same dataset for
the same training time, compared as in :mod:`affnerf.bench.curves` (step time measured alone, budgets in steps,
chunks scored on the `val` objects). Run:

    .venv/bin/python benchmarks/bench_training_curves.py [--minutes 12] [--chunks 4]

Writes ``benchmarks/results/training_curves.json`` and prints both curves.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

from affnerf.bench.curves import measure_curve, step_seconds
from affnerf.bench.training import reference_variant
from affnerf.environment import describe_machine
from affnerf.train.cache import load_frames
from affnerf.train.config import SMALL
from affnerf.train.trainer import train

HERE = Path(__file__).parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=float, default=12.0)
    parser.add_argument("--chunks", type=int, default=4)
    parser.add_argument("--data", type=Path, default=HERE / ".work" / "small_config" / "data")
    parser.add_argument("--work", type=Path, default=HERE / ".work" / "training_curves")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "training_curves.json")
    args = parser.parse_args()
    runs = args.work / "runs"
    fast = replace(SMALL, data=args.data, cache_dir=runs / "cache", image_scale=0.25)
    m = fast.model
    reference = reference_variant(replace(fast, model=replace(m, num_coarse=2 * m.num_coarse, num_fine=2 * m.num_fine)))
    train(
        replace(
            fast,
            out=runs / "warmup",
            steps=1,
            val_every=0,
            progress=False,
            resume=(runs / "warmup" / "checkpoints").is_dir(),
        )
    )
    frames = [load_frames(p) for p in sorted((runs / "cache").iterdir()) if (p / "meta.json").is_file()]
    timing = {"reference": step_seconds(reference, frames), "fast": step_seconds(fast, frames)}
    print("seconds per step:", timing, flush=True)
    started = time.time()
    result = {"benchmark": "training_curves", "machine": describe_machine(), "minutes": args.minutes, "paths": {}}
    for name, config in (("reference", reference), ("fast", fast)):
        result["paths"][name] = measure_curve(replace(config, out=runs / name), args.minutes, args.chunks, timing[name])
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(result, indent=1) + "\n")
    ref, fst = result["paths"]["reference"], result["paths"]["fast"]
    result["speedup_rays_per_second"] = fst["rays_per_second"] / ref["rays_per_second"]
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    for name in ("reference", "fast"):
        curve = " ".join(f"{p['train_seconds']:.0f}s:{p['val_mIoU']:.3f}" for p in result["paths"][name]["curve"])
        print(f"{name}: {result['paths'][name]['rays_per_second']:.0f} rays/s; val mIoU {curve}")
    print(f"speed-up x{result['speedup_rays_per_second']:.1f}; {time.time() - started:.0f} s -> {args.out}")


if __name__ == "__main__":
    main()
