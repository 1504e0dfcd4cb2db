"""How well a pose-aware model predicts the input camera from one crop: the error of its camera head per category.

For every object of a split (at most ``--max-objects`` per category) and ``--views`` of its frames, the model
encodes the frame's crop alone and its predicted camera (conventions §4, pose-aware model) is compared with the
frame's true pose: elevation and azimuth error in degrees, the distance's |log ratio|, and how far the predicted
origin lies from the true one in the crop, as a fraction of the crop side. Rotationally symmetric families
(bottle, bucket) have no defined azimuth: their azimuth error is reported but says nothing.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/camera_accuracy.py --run RUN --data DATA \\
        [--split test] [--max-objects 5] [--views 4] [--out benchmarks/results/camera_accuracy.json]

Writes JSON: per category the mean and median of each error and the share of azimuths within 30 degrees.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset
from affnerf.environment import describe_machine
from affnerf.fileio import write_json_atomic
from affnerf.model.inputs import dataset_views
from affnerf.predict.loading import load_model


def object_errors(model, obj, views: list[int]) -> dict[str, np.ndarray]:
    """Errors of the camera predicted from each of ``views`` of ``obj``, each crop encoded alone -> name: (V,)."""
    images, intr, poses = dataset_views(obj, views, model.config)
    with torch.no_grad():
        encoding = model.encode_views(images[0][:, None], intr[0][:, None], poses[0][:, None])
        return {k: v.numpy() for k, v in model.camera_errors(encoding).items()}


def summarise(errors: dict[str, list[float]]) -> dict[str, float]:
    """Mean and median of each error, and the share of azimuth errors under 30 degrees."""
    out: dict[str, float] = {}
    for name, values in errors.items():
        arr = np.asarray(values)
        out[f"{name}_mean"] = round(float(arr.mean()), 4)
        out[f"{name}_median"] = round(float(np.median(arr)), 4)
    out["azimuth_within_30deg"] = round(float((np.asarray(errors["azimuth_deg"]) < 30.0).mean()), 4)
    out["crops"] = len(errors["azimuth_deg"])
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--run", type=Path, required=True)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--split", default="test")
    parser.add_argument("--max-objects", type=int, default=5)
    parser.add_argument("--views", type=int, default=4)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/camera_accuracy.json"))
    args = parser.parse_args()
    started = time.perf_counter()
    loaded = load_model(args.run)
    if not hasattr(loaded.model, "camera_errors"):
        raise SystemExit(f"{loaded.path}: a {loaded.model.config.kind} model predicts no input camera")
    ds = Dataset.open(args.data)
    per_category: dict[str, dict[str, list[float]]] = {}
    for category in ds.categories:
        for entry in ds.objects(args.split, [category])[: args.max_objects]:
            obj = ds.load_object(entry)
            step = max(1, len(obj) // args.views)
            errors = object_errors(loaded.model, obj, list(range(0, len(obj), step))[: args.views])
            bucket = per_category.setdefault(category, {})
            for name, values in errors.items():
                bucket.setdefault(name, []).extend(values.tolist())
    report = {
        "checkpoint": str(loaded.path),
        "step": loaded.step,
        "split": args.split,
        "categories": {c: summarise(e) for c, e in per_category.items()},
        "machine": describe_machine(),
        "seconds": round(time.perf_counter() - started, 1),
    }
    write_json_atomic(args.out, report)
    for category, row in report["categories"].items():
        print(
            f"{category:12s} azimuth {row['azimuth_deg_median']:6.1f}° median ({row['azimuth_within_30deg']:.0%} "
            f"< 30°)  elevation {row['elevation_deg_median']:5.1f}°  origin {row['principal_median']:.3f} S"
        )


if __name__ == "__main__":
    main()
