"""The mesh level of a model on held-out objects: one calibrated density for every object against the per-object
level (``surface_optical_depth``, :mod:`affnerf.predict.level`), side by side on the same grids (issue 12).

For each of the first ``--max-objects`` objects of the split (round-robin over categories, as Table 2), the object
is encoded from the protocol's seeded input view, its density grid is evaluated once at ``--resolution`` (as
``affnerf eval`` does), and marching cubes at each rule gives the labelled mesh scored against the true mesh:
F-score at 1 cm, 3D affordance mIoU, Chamfer-L1 (conventions §5). Both rules use the model's stored
``surface_density``; the per-object rule uses ``--optical-depth`` (default: the model's stored value).

Usage::

    python benchmarks/mesh_level.py --checkpoint RUN_OR_CKPT --data DATA --out benchmarks/results/mesh_level
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from affnerf.data.dataset import Dataset
from affnerf.environment import describe_machine
from affnerf.eval.calibrate import (
    CalibrateConfig,
    calibration_grids,
    calibration_objects,
    sweep_optical_depths,
)
from affnerf.eval.calibration_choice import summarise_optical_depths
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.predict.loading import load_model


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--checkpoint", required=True, help="run folder or checkpoint file")
    parser.add_argument("--data", required=True)
    parser.add_argument("--out", required=True, help="writes OUT.json and OUT.md")
    parser.add_argument("--split", default="test")
    parser.add_argument("--max-objects", type=int, default=40)
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--optical-depth", type=float, default=None)
    parser.add_argument("--note", default="", help="appended to the provenance line (what the checkpoint is)")
    return parser.parse_args()


def per_category(
    categories: list[str], scores: list[list[dict]], depths: tuple[float, float], rules: list[str]
) -> dict:
    """Per category and rule, the mean of each 3D metric (Chamfer over non-empty meshes)."""
    table: dict[str, Any] = {}
    for cat in sorted(set(categories)):
        rows = [s for s, c in zip(scores, categories, strict=True) if c == cat]
        table[cat] = dict(zip(rules, summarise_optical_depths(depths, rows), strict=True))
    return table


def markdown(result: dict) -> str:
    rules = result["rules"]
    head = "| category | " + " | ".join(f"{r}: F@1cm / 3D mIoU / Chamfer (m)" for r in rules) + " |"
    lines = [result["provenance"], "", head, "| --- |" + " --- |" * len(rules)]
    cells = lambda row: " | ".join(  # noqa: E731
        f"{row[r]['fscore_1cm']:.3f} / {row[r]['affordance_miou_3d']:.3f} / "
        + ("–" if row[r]["chamfer_l1"] is None else f"{row[r]['chamfer_l1']:.4f}")
        for r in rules
    )
    for cat, row in result["categories"].items():
        lines.append(f"| {cat} | {cells(row)} |")
    lines.append(f"| **mean** | {cells(result['mean'])} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    args = parse()
    start = time.perf_counter()
    loaded = load_model(Path(args.checkpoint), "cpu")
    config = loaded.model.config
    depth = config.surface_optical_depth if args.optical_depth is None else args.optical_depth
    ds = Dataset.open(args.data)
    objects = calibration_objects(ds, args.split, args.max_objects)
    method = ConditionedNeRFMethod(loaded, mesh_resolution=args.resolution)
    grids, views = calibration_grids(method, objects, CalibrateConfig(data=Path(args.data)))
    half = config.scene_half_extent
    scores = [sweep_optical_depths(g, (0.0, depth), config.surface_density, half) for g in grids]
    rules = [f"fixed {config.surface_density:g}/m", f"per-object (optical depth {depth:g})"]
    categories = [o.record.category for o in objects]
    result = {
        "benchmark": "mesh_level",
        "machine": describe_machine(),
        "checkpoint": str(loaded.path),
        "split": args.split,
        "resolution": args.resolution,
        "rules": rules,
        "objects": {
            o.record.object_id: {"views": views[o.record.object_id], "scores": s}
            for o, s in zip(objects, scores, strict=True)
        },  # fmt: skip
        "categories": per_category(categories, scores, (0.0, depth), rules),
        "mean": dict(zip(rules, summarise_optical_depths((0.0, depth), scores), strict=True)),
        "seconds": round(time.perf_counter() - start, 1),
    }
    m = describe_machine()
    result["provenance"] = (
        f"> {m['date'][:10]}, {m['cpu_count']}-core CPU, torch {m['torch']}. {len(objects)} {args.split} objects "
        f"(first per category, round-robin), 1 seeded input view (the Table 2 protocol), grid {args.resolution}^3, "
        f"{result['seconds']:.0f} s. Checkpoint {Path(args.checkpoint).name}; "
        f"mean per-object level {np.mean([s[1]['level'] for s in scores]):.1f}/m. {args.note}"
    ).rstrip()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    out.with_suffix(".md").write_text(markdown(result))
    print(markdown(result))


if __name__ == "__main__":
    main()
