"""How the labelled mesh's vertices get their affordance: rules compared on the same meshes (issue 12, 3D mIoU).

Today each vertex takes the argmax of the field's affordance logits at the vertex itself. The surface is where the
density crosses the mesh level, which is also where the affordance head is least constrained (rendering sees it
through the opacity; the 3D supervision's labels change across a part boundary right there). Two rules that cost
no training are compared with it, each on the same mesh of each object:

- ``inward D``: the class probabilities averaged over the vertex and points ``D`` and ``D/2`` metres inside the
  surface along the vertex normal (the object's interior, where the nearest-face labels of the 3D supervision hold);
- ``smooth K``: the vertex probabilities averaged ``K`` times with those of the mesh neighbours (a graph
  low-pass: a speckle of one class inside another is voted away), then the argmax;
- both together.

For each of the first ``--max-objects`` objects of the split (round-robin over categories), the object is encoded
from the protocol's seeded input view, the density grid is evaluated once and cut at the object's own level (as
``affnerf eval``), and each rule's labelled mesh is scored against the true mesh (3D affordance mIoU, conventions
§5; F-score and Chamfer do not change with the labels).

Usage::

    python benchmarks/mesh_labels.py --checkpoint RUN_OR_CKPT --data DATA --split val --out OUT
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch
import trimesh
from scipy import sparse

from affnerf.data.dataset import Dataset
from affnerf.environment import describe_machine
from affnerf.eval.calibrate import calibration_objects, input_views
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.surface import sample_seed, score_mesh, true_samples
from affnerf.meshio import LabelledMesh, majority_face_labels
from affnerf.predict.invert import point_labels
from affnerf.predict.loading import load_model
from affnerf.predict.mesh import evaluate_grid, marching_cubes, model_level


def neighbour_mean_operator(faces: np.ndarray, count: int) -> sparse.csr_matrix:
    """(V, V) sparse row-stochastic matrix averaging each vertex with its edge neighbours (itself included,
    each distinct neighbour once); ``count`` = V.

    Example:
        >>> m = neighbour_mean_operator(np.array([[0, 1, 2]]), 4)
        >>> m.toarray()[0].tolist(), m.toarray()[3].tolist()
        ([0.3333333333333333, 0.3333333333333333, 0.3333333333333333, 0.0], [0.0, 0.0, 0.0, 1.0])
    """
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    rows = np.concatenate([edges[:, 0], edges[:, 1], np.arange(count)])
    cols = np.concatenate([edges[:, 1], edges[:, 0], np.arange(count)])
    adjacency = sparse.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(count, count)).tocsr()
    adjacency.data[:] = 1.0  # an edge shared by two faces counts once
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    return sparse.diags(1.0 / degree) @ adjacency


def smooth_on_mesh(values: np.ndarray, faces: np.ndarray, iterations: int) -> np.ndarray:
    """(V, C) per-vertex values averaged ``iterations`` times with their edge neighbours' (a graph low-pass:
    an isolated vertex of one class among another's takes its neighbours' class).

    Example:
        >>> faces = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1]])
        >>> p = np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 0.0], [1.0, 0.0]])  # vertex 0 disagrees with all
        >>> smooth_on_mesh(p, faces, 2).argmax(axis=1).tolist()
        [0, 0, 0, 0]
    """
    if iterations <= 0 or not len(faces):
        return values
    op = neighbour_mean_operator(faces, len(values))
    out = np.asarray(values, np.float64)
    for _ in range(iterations):
        out = op @ out
    return out


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--checkpoint", required=True, help="run folder or checkpoint file")
    parser.add_argument("--data", required=True)
    parser.add_argument("--out", required=True, help="writes OUT.json and OUT.md")
    parser.add_argument("--split", default="val")
    parser.add_argument("--max-objects", type=int, default=40)
    parser.add_argument("--resolution", type=int, default=96)
    parser.add_argument("--depths", default="0.005,0.01,0.02", help="inward distances, metres")
    parser.add_argument("--smooth", default="2,5,10,20", help="smoothing iterations")
    return parser.parse_args()


@torch.no_grad()
def probabilities(model, encoding, points: np.ndarray, chunk: int = 32768) -> np.ndarray:
    """(N, C) softmax of the field's object-class logits (:func:`affnerf.predict.invert.point_labels`) at (N, 3)
    points."""
    out = [
        torch.softmax(point_labels(model, encoding, torch.from_numpy(points[s : s + chunk]).float()), dim=-1).numpy()
        for s in range(0, len(points), chunk)
    ]
    return np.concatenate(out)


def labelled(vertices: np.ndarray, faces: np.ndarray, probs: np.ndarray) -> LabelledMesh:
    labels = probs.argmax(axis=1) + 1
    return LabelledMesh(
        vertices=vertices,
        faces=faces,
        vertex_props={"affordance": labels.astype(np.uint8)},
        face_props={"affordance": majority_face_labels(faces, labels).astype(np.uint8)},
    )


def rule_probabilities(model, encoding, vertices, faces, depths, smooth) -> dict[str, np.ndarray]:
    """Each rule's (V, C) vertex probabilities."""
    normals = np.asarray(trimesh.Trimesh(vertices, faces, process=False).vertex_normals)  # outward
    at = probabilities(model, encoding, vertices)
    rules = {"vertex (today)": at}
    inward = {}
    for d in depths:
        deeper = [probabilities(model, encoding, vertices - f * d * normals) for f in (0.5, 1.0)]
        inward[d] = (at + deeper[0] + deeper[1]) / 3.0
        rules[f"inward {d * 100:g} cm"] = inward[d]
    for k in smooth:
        rules[f"smooth {k}"] = smooth_on_mesh(at, faces, k)
    for d in depths:
        for k in smooth:
            rules[f"inward {d * 100:g} cm + smooth {k}"] = smooth_on_mesh(inward[d], faces, k)
    return rules


def score_object(method, obj, args, depths, smooth) -> dict[str, float | None]:
    model = method.loaded.model
    inputs = input_views(obj, 1, 0)
    encoding, grid = method.encoded(obj, inputs), method.occupancy(obj, inputs)
    density, _ = model.point_fields(encoding)
    half = model.config.scene_half_extent
    volume = evaluate_grid(density, args.resolution, half, occupancy=grid)
    level = model_level(model, volume)
    vertices, faces = marching_cubes(volume, level, half)
    truth, seed = true_samples(obj, 0), sample_seed(0, obj.record.object_id)
    if not len(faces):
        return {}
    rules = rule_probabilities(model, encoding, vertices, faces, depths, smooth)
    scores = {name: score_mesh(labelled(vertices, faces, p), truth, seed) for name, p in rules.items()}
    return {name: s["affordance_miou_3d"] for name, s in scores.items()}


def main() -> None:
    args = parse()
    start = time.perf_counter()
    loaded = load_model(Path(args.checkpoint), "cpu")
    method = ConditionedNeRFMethod(loaded, mesh_resolution=args.resolution)
    ds = Dataset.open(args.data)
    objects = calibration_objects(ds, args.split, args.max_objects)
    depths = [float(x) for x in args.depths.split(",")]
    smooth = [int(x) for x in args.smooth.split(",")]
    rows = {}
    for obj in objects:
        rows[obj.record.object_id] = score_object(method, obj, args, depths, smooth)
        print(obj.record.object_id, {k: round(v, 3) for k, v in rows[obj.record.object_id].items() if v is not None})
    names = list(next(r for r in rows.values() if r))
    cats = sorted({o.record.category for o in objects})

    def mean(name, cat=None):
        vals = [
            r.get(name)
            for oid, r in rows.items()
            if (cat is None or oid.rsplit("_", 1)[0] == cat) and r.get(name) is not None
        ]
        return float(np.mean(vals)) if vals else None

    table = {n: {"mean": mean(n), **{c: mean(n, c) for c in cats}} for n in names}
    m = describe_machine()
    result = {
        "benchmark": "mesh_labels",
        "machine": m,
        "checkpoint": str(loaded.path),
        "split": args.split,
        "objects": len(objects),
        "resolution": args.resolution,
        "rules": table,
        "per_object": rows,
        "seconds": round(time.perf_counter() - start, 1),
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    lines = ["| rule | mean | " + " | ".join(cats) + " |", "| --- |" + " --- |" * (len(cats) + 1)]
    for n in names:
        lines.append(f"| {n} | " + " | ".join(f"{table[n][k]:.3f}" for k in ["mean", *cats]) + " |")
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
