"""How good is the camera the fit to the photo finds (``prediction.json``: ``fit.camera``)? Per category, on
dataset views whose true camera is known.

For the first ``--max-objects`` objects per category of a split and each one's protocol input view (conventions
§5, seed 0), the model encodes the view and fits its codes to it (:mod:`affnerf.predict.invert`, the defaults of
``affnerf predict``; the view's intrinsics are used, never its pose). The camera found is compared with the view's
true camera-to-canonical pose: the angle between the two rotations, the azimuth and elevation errors, the
distance's |log ratio|, and the distance between the two camera centres (canonical metres). Rotationally
symmetric families (bottle, bucket) have no defined azimuth: their azimuth and rotation errors say little.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/fit_camera_accuracy.py --data DATA \\
        [--run src/affnerf/weights/affnerf-small.pt] [--split test] [--max-objects 5] \\
        [--out benchmarks/results/fit_camera_accuracy.json]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.environment import describe_machine
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.fileio import write_json_atomic
from affnerf.model.inputs import dataset_views
from affnerf.predict.invert import InversionConfig, InversionResult, dataset_crop_target, invert
from affnerf.predict.loading import load_model
from affnerf.predict.shipped import shipped_model


def camera_errors(result: InversionResult, true_c2w: np.ndarray) -> dict[str, float]:
    """Errors of the camera a fit found against a true (4, 4) camera-to-canonical pose."""
    found, pose = result.camera, result.camera_to_world()
    eye = true_c2w[:3, 3]
    azimuth, elevation = math.atan2(eye[1], eye[0]), math.asin(eye[2] / np.linalg.norm(eye))
    cos = (np.trace(pose[:3, :3].T @ true_c2w[:3, :3]) - 1.0) / 2.0
    return {
        "rotation_deg": math.degrees(math.acos(float(np.clip(cos, -1.0, 1.0)))),
        "azimuth_deg": math.degrees(abs((found[0] - azimuth + math.pi) % (2 * math.pi) - math.pi)),
        "elevation_deg": math.degrees(abs(found[1] - elevation)),
        "distance_log_ratio": abs(math.log(found[2] / np.linalg.norm(eye))),
        "centre_m": float(np.linalg.norm(pose[:3, 3] - eye)),
    }


def summarise(rows: list[dict[str, float]]) -> dict[str, float]:
    """Median of each error, and the shares of rotations and elevations within 30 and 15 degrees."""
    out = {f"{k}_median": round(float(np.median([r[k] for r in rows])), 4) for k in rows[0]}
    out["rotation_within_30deg"] = round(float(np.mean([r["rotation_deg"] < 30 for r in rows])), 4)
    out["elevation_within_15deg"] = round(float(np.mean([r["elevation_deg"] < 15 for r in rows])), 4)
    out["views"] = len(rows)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--run", type=Path, default=shipped_model())
    parser.add_argument("--split", default="test")
    parser.add_argument("--max-objects", type=int, default=5)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "fit_camera_accuracy.json")
    args = parser.parse_args()
    started = time.perf_counter()
    ds = Dataset.open(args.data)
    loaded = load_model(args.run, torch.device("cpu"))
    model, size = loaded.model.eval(), loaded.model.config.encoder_resolution
    per_category: dict[str, list[dict[str, float]]] = {}
    for entry in interleave_categories(ds.objects(args.split), args.max_objects):
        obj = ds.load_object(entry)
        view = choose_views(len(obj), obj.record.object_id, ProtocolConfig())[0][0]
        images, intr, poses = dataset_views(obj, [view], model.config)
        with torch.no_grad():
            codes = model.encode_views(images, intr, poses)
        target = dataset_crop_target(obj, view, size)
        result = invert(model, codes, target, np.asarray(loaded.background), InversionConfig(seed=view))
        errors = camera_errors(result, obj.pose(view))
        per_category.setdefault(obj.record.category, []).append(errors)
        print(f"{obj.record.object_id:18s} " + " ".join(f"{k} {v:.3f}" for k, v in errors.items()), flush=True)
    every = [r for rows in per_category.values() for r in rows]
    result = {
        "benchmark": "fit_camera_accuracy",
        "settings": {
            "run": str(args.run),
            "split": args.split,
            "max_objects": args.max_objects,
            "inversion": "InversionConfig() defaults (affnerf predict)",
        },  # fmt: skip
        "machine": describe_machine(),
        "seconds": round(time.perf_counter() - started, 1),
        "categories": {c: summarise(rows) for c, rows in sorted(per_category.items())},
        "all": summarise(every),
    }
    write_json_atomic(args.out, result)
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
