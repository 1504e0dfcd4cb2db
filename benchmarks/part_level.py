"""Can a thin part lost at the mesh level be recovered at extraction? (issues 12 and 13; results/part_level.md)

A predicted bucket's bail has a density of 0.1-0.4 × the mesh level at the true bail's surface (median over its
surface samples, 5 test buckets), so marching cubes at the level loses it, and with it every grasp on it. This
lowers the level only where the field says the point belongs to the hand-held part: the density grid is scaled
by ``1 + (1/f - 1) p`` before marching cubes at the object's own level, ``p`` the field's probability of
``grasp`` plus ``pull`` at the grid point (continuous, so no seam where the label flips), ``f`` the factor the
level is lowered to where ``p`` = 1 (1 = today). Each factor's mesh is scored against the true mesh: F@1cm,
precision and recall, the recall of the true ``grasp``/``pull`` surface (share of its samples within 1 cm of the
predicted surface) and 3D affordance mIoU, each object encoded from the protocol's seeded input view.

    .venv/bin/python benchmarks/part_level.py --data DATA --checkpoint src/affnerf/weights/affnerf-small.pt \
        --split val --per-category 5 --out benchmarks/results/part_level.json
"""

from __future__ import annotations

import argparse
import json
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
from surface_errors import object_errors

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.environment import describe_machine
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.eval.surface import mesh_samples, sample_seed, score_mesh, true_samples
from affnerf.predict.loading import load_model
from affnerf.predict.mesh import evaluate_grid, labelled_mesh_from_grid, model_level
from affnerf.vocab import affordance_id

#: The parts a gripper holds, whose level is lowered.
HELD = ("grasp", "pull")


def factor_meshes(model, encoding, resolution: int, factors: list[float]) -> dict[float, object]:
    """The labelled mesh of one encoded object for each factor (1 = the mesh ``affnerf eval`` makes)."""
    density, labels = model.point_fields(encoding)
    probabilities = model.point_probabilities(encoding)
    held = [affordance_id(name) - 1 for name in HELD]  # columns of the object classes, which start at 1
    half = model.config.scene_half_extent
    volume = evaluate_grid(density, resolution, half)
    p_held = evaluate_grid(lambda x: probabilities(x)[:, held].sum(-1), resolution, half)
    level = model_level(model, volume)
    return {f: labelled_mesh_from_grid(volume * (1.0 + (1.0 / f - 1.0) * p_held), labels, level, half) for f in factors}


def held_recall(part_recall: dict[str, float]) -> float | None:
    """The recall of the true held part (``grasp``, else ``pull``); None for a family without one."""
    return next((part_recall[name] for name in HELD if name in part_recall), None)


def summarise(rows: list[dict], factors: list[float]) -> dict:
    """Per factor: the means over objects, and per category, of F, precision, recall, held recall and 3D mIoU."""
    keys = ("fscore", "precision", "recall", "held_recall", "miou3d")
    out: dict = {}
    for f in factors:
        groups: dict[str, list[dict]] = defaultdict(list)
        for row in rows:
            if row["factor"] == f:
                groups[row["category"]].append(row)
                groups["mean"].append(row)

        def mean(group: list[dict], key: str) -> float | None:
            values = [r[key] for r in group if r[key] is not None]
            return float(np.mean(values)) if values else None

        out[str(f)] = {name: {k: mean(group, k) for k in keys} for name, group in sorted(groups.items())}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--checkpoint", type=Path, required=True)
    parser.add_argument("--split", default="val")
    parser.add_argument("--per-category", type=int, default=5)
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--factors", default="1,0.5,0.3,0.2")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    started = time.perf_counter()
    factors = [float(x) for x in args.factors.split(",")]
    ds = Dataset.open(args.data)
    method = ConditionedNeRFMethod(load_model(args.checkpoint, "cpu"), mesh_resolution=args.resolution)
    protocol = ProtocolConfig(input_views=1, target_views=0)
    rows = []
    for entry in interleave_categories(ds.objects(args.split), args.per_category):
        obj = ds.load_object(entry)
        inputs = choose_views(len(obj), obj.record.object_id, protocol)[0]
        truth, seed = true_samples(obj, protocol.seed), sample_seed(protocol.seed, obj.record.object_id)
        for f, mesh in factor_meshes(
            method.loaded.model, method.encoded(obj, inputs), args.resolution, factors
        ).items():
            errors = object_errors(mesh_samples(mesh, seed).points, truth.points, truth.labels)
            row = {"object": obj.record.object_id, "category": entry.category, "factor": f}
            row |= {k: errors[k] for k in ("fscore", "precision", "recall")}
            row |= {"held_recall": held_recall(errors["part_recall"])}
            row |= {"miou3d": score_mesh(mesh, truth, seed)["affordance_miou_3d"]}
            rows.append(row)
        print(obj.record.object_id, flush=True)
    result = {"benchmark": "part_level", "machine": describe_machine(), "settings": {**vars(args)}}
    result["settings"] = {k: str(v) for k, v in result["settings"].items()}
    result |= {"summary": summarise(rows, factors), "objects": rows, "seconds": round(time.perf_counter() - started, 1)}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    for f, cats in result["summary"].items():
        print(
            f,
            {c: {k: None if v is None else round(v, 3) for k, v in m.items()} for c, m in cats.items() if c == "mean"},
        )


if __name__ == "__main__":
    main()
