"""Where the predicted meshes lose their F-score (issues 12 and 13; benchmarks/results/surface_errors.md).

F@1cm mixes two failures: predicted surface where there is none (precision) and true surface that was not
predicted (recall). For each object (the protocol's seeded input view, the method's mesh as ``affnerf eval`` makes
it), this scores both at 1 cm and, from the true side, the recall of each affordance part on its own: the share of
the true part's surface samples within 1 cm of the predicted surface. A bail, a handle or a temple that the mesh
does not have shows as a part recall near 0 whatever the body scores. Beside them, the volume: of points drawn
uniformly in the true object's convex hull, the share of those inside the true mesh that the predicted mesh also
encloses (``solid``), and of those outside it (the cavity of a bucket or a cabinet, the gap under a handle) the share
the predicted mesh fills (``cavity_filled``), both by :func:`affnerf.solid.inside_mesh`.

    .venv/bin/python benchmarks/surface_errors.py --data DATA --run src/affnerf/weights/affnerf-small.pt \
        --methods affnerf,retrieval --out OUT.json [--split test --per-category 5 --resolution 128]
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from dataclasses import replace
from pathlib import Path

import numpy as np
import trimesh

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.eval.runner import EvalConfig, build_method
from affnerf.eval.surface import mesh_samples, method_mesh, sample_seed, true_samples
from affnerf.meshio import LabelledMesh, read_labelled_ply
from affnerf.metrics.surface import FSCORE_TAU, fscore_from_distances, nearest
from affnerf.solid import inside_mesh
from affnerf.vocab import AFFORDANCE_CLASSES


def object_errors(pred_points: np.ndarray, true_points: np.ndarray, true_labels: np.ndarray) -> dict:
    """Precision, recall and F at 1 cm of (N, 3) predicted against (M, 3) true surface samples, and the recall of
    each true affordance label (its samples within 1 cm of a predicted one); all 0 for an empty prediction.

    Example:
        >>> e = object_errors(np.zeros((1, 3)), np.array([[0.0, 0, 0.005], [0, 0, 0.5]]), np.array([1, 6]))
        >>> e["precision"], e["recall"], e["part_recall"]
        (1.0, 0.5, {'grasp': 1.0, 'pull': 0.0})
    """
    names = {int(k): AFFORDANCE_CLASSES[int(k)] for k in np.unique(true_labels)}
    if len(pred_points) == 0:
        return {"precision": 0.0, "recall": 0.0, "fscore": 0.0, "part_recall": {n: 0.0 for n in names.values()}}
    to_true, _ = nearest(pred_points, true_points)
    to_pred, _ = nearest(true_points, pred_points)
    hit = to_pred <= FSCORE_TAU
    return {
        "precision": float((to_true <= FSCORE_TAU).mean()),
        "recall": float(hit.mean()),
        "fscore": fscore_from_distances(to_true, to_pred),
        "part_recall": {name: float(hit[true_labels == k].mean()) for k, name in names.items()},
    }


#: Points drawn in each true object's convex hull for the volume measures.
VOLUME_POINTS = 4000


def hull_points(true_mesh: LabelledMesh, seed: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """(P, 3) points uniform in the true mesh's convex hull and (P,) whether each is inside the true mesh."""
    tm = trimesh.Trimesh(true_mesh.vertices, true_mesh.faces, process=False)
    hull = tm.convex_hull
    rng = np.random.default_rng(seed)
    lo, hi = hull.bounds
    box = rng.uniform(lo, hi, (VOLUME_POINTS * 4, 3))
    points = box[hull.contains(box)][:VOLUME_POINTS]
    return points, inside_mesh(tm, points)


def volume_errors(pred_mesh: LabelledMesh | None, points: np.ndarray, inside: np.ndarray) -> dict:
    """``solid``: share of the true inside points the predicted mesh encloses; ``cavity_filled``: share of the
    hull points outside the true mesh that it encloses (None when the hull has none); 0 for no prediction."""
    if pred_mesh is None or len(pred_mesh.faces) == 0:
        enclosed = np.zeros(len(points), bool)
    else:
        enclosed = inside_mesh(trimesh.Trimesh(pred_mesh.vertices, pred_mesh.faces, process=False), points)
    cavity = ~inside
    return {
        "solid": float(enclosed[inside].mean()) if inside.any() else None,
        "cavity_filled": float(enclosed[cavity].mean()) if cavity.sum() >= 20 else None,
        "cavity_share": float(cavity.mean()),
    }


def summarise(rows: list[dict]) -> dict:
    """Per category and method: mean precision, recall and F, and each part's mean recall over the objects."""
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for row in rows:
        groups[(row["method"], row["category"])].append(row)
    out: dict = defaultdict(dict)
    for (method, category), group in sorted(groups.items()):
        parts: dict[str, list[float]] = defaultdict(list)
        for row in group:
            for name, value in row["part_recall"].items():
                parts[name].append(value)
        volume = {k: [r[k] for r in group if r[k] is not None] for k in ("solid", "cavity_filled", "cavity_share")}
        out[method][category] = {
            **{k: float(np.mean([r[k] for r in group])) for k in ("precision", "recall", "fscore")},
            **{k: float(np.mean(v)) if v else None for k, v in volume.items()},
            "part_recall": {name: float(np.mean(v)) for name, v in sorted(parts.items())},
            "objects": len(group),
        }
    return dict(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--run", type=Path, required=True)
    parser.add_argument("--methods", default="affnerf,retrieval")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--split", default="test")
    parser.add_argument("--per-category", type=int, default=5)
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument(
        "--surface-optical-depth", type=float, default=None, help="override the model's per-object level (0 = off)"
    )
    args = parser.parse_args()
    ds = Dataset.open(args.data)
    config = EvalConfig(args.run, args.data, args.out.parent, device="cpu", mesh_resolution=args.resolution)
    methods = [build_method(name, config, ds) for name in args.methods.split(",")]
    for method in methods:
        loaded = getattr(method, "loaded", None)
        if args.surface_optical_depth is not None and loaded is not None:
            model = loaded.model
            model.config = replace(model.config, surface_optical_depth=args.surface_optical_depth)
    protocol = ProtocolConfig(input_views=1, target_views=0)
    rows = []
    for entry in interleave_categories(ds.objects(args.split), args.per_category):
        obj = ds.load_object(entry)
        inputs = choose_views(len(obj), obj.record.object_id, protocol)[0]
        truth = true_samples(obj, protocol.seed)
        seed = sample_seed(protocol.seed, obj.record.object_id)
        points, inside = hull_points(read_labelled_ply(obj.folder / "mesh.ply"), seed)
        for method in methods:
            mesh = method_mesh(method, obj, inputs)
            errors = object_errors(mesh_samples(mesh, seed).points, truth.points, truth.labels)
            errors |= volume_errors(mesh, points, inside)
            rows.append({"object": obj.record.object_id, "category": entry.category, "method": method.name, **errors})
    result = {"settings": vars(args) | {"data": str(args.data), "run": str(args.run), "out": str(args.out)}}
    result |= {"summary": summarise(rows), "objects": rows}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    for method, cats in result["summary"].items():
        for category, s in cats.items():
            parts = ", ".join(f"{n} {v:.2f}" for n, v in s["part_recall"].items())
            scores = f"P {s['precision']:.2f} R {s['recall']:.2f} F {s['fscore']:.2f}"
            cavity = "-" if s["cavity_filled"] is None else f"{s['cavity_filled']:.2f}"
            scores += f" solid {s['solid']:.2f} cavity {cavity} ({s['cavity_share']:.2f} of hull)"
            print(f"{method:10s} {category:12s} {scores} | {parts}")


if __name__ == "__main__":
    main()
