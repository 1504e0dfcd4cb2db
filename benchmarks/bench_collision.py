"""The planner's collision check against testing every surface point in every grasp: same answers, time.

``affnerf.grasp.planner.collides`` tests only the points within the gripper's reach of each grasp centre (a k-d tree
query). This times it, side by side in one process, against the dense test it replaced (every point transformed
into every grasp frame and tested against the fingers and the palm), on the meshes a planner sees: the dataset's
true meshes at their metric size, and labelled meshes predicted from one image (``--meshes``, e.g. a ``make demo``
output's ``*/affordance_model.ply``, at their category's typical size). Each object gets the planner's load: 256 grasp
frames (64 pairs x 4 approaches) near its surface, at random openings, against 1,500 surface samples and its vertices.

Run::

    .venv/bin/python benchmarks/bench_collision.py --data DATA [--per-category 2] \
        [--meshes 'demo_out/*/affordance_model.ply']

Writes ``benchmarks/results/collision_check.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import glob
import json
import time
from pathlib import Path

import numpy as np

from affnerf.environment import describe_machine
from affnerf.grasp.gripper import ParallelJawGripper, grasp_pose
from affnerf.grasp.planner import collides
from affnerf.grasp.size import resolve_size, scaled
from affnerf.grasp.target import GraspObject, load_grasp_object

RESULTS = Path(__file__).resolve().parent / "results"


def dense_collides(poses, widths, gripper, points, tolerance, chunk=32):
    """The check as it was: (G,) bool, every point of (P, 3) in every grasp frame of (G, 4, 4)."""
    hit = np.zeros(len(poses), bool)
    for start in range(0, len(poses), chunk):
        pose = poses[start : start + chunk]
        local = np.einsum("gji,gpj->gpi", pose[:, :3, :3], points[None] - pose[:, None, :3, 3])
        for k in range(3):
            boxes = [gripper.boxes(w)[k] for w in widths[start : start + chunk]]
            centre = np.stack([b[0] for b in boxes])[:, None]
            half = np.stack([b[1] for b in boxes])[:, None]
            hit[start : start + chunk] |= np.all(np.abs(local - centre) < half - tolerance, axis=2).any(axis=1)
    return hit


def load(path: Path, category: str | None) -> GraspObject:
    """A mesh at its metric size (the dataset's scale, else the category's typical size)."""
    obj = load_grasp_object(path)
    size = resolve_size(path, obj.vertices, None, category)
    return scaled(obj, size.factor)


def one_object(obj: GraspObject, gripper: ParallelJawGripper, rng: np.random.Generator) -> dict:
    """Both checks on the planner's load for one object: times (s), hits and disagreements."""
    points = np.concatenate([obj.sample_surface(1500, rng)[0], obj.vertices])
    centres = obj.vertices[rng.integers(len(obj.vertices), size=256)] + rng.normal(0, 0.005, (256, 3))
    poses = np.stack([grasp_pose(c, rng.normal(size=3), rng.normal(size=3)) for c in centres])
    widths = rng.uniform(0.0, gripper.max_opening, 256)
    start = time.perf_counter()
    dense = dense_collides(poses, widths, gripper, points, 0.001)
    dense_s = time.perf_counter() - start
    start = time.perf_counter()
    tree = collides(poses, widths, gripper, points, 0.001)
    tree_s = time.perf_counter() - start
    return {
        "points": len(points),
        "hits": int(dense.sum()),
        "differ": int((dense != tree).sum()),
        "dense_s": round(dense_s, 4),
        "tree_s": round(tree_s, 4),
    }


def report(rows: list[dict], machine: dict) -> str:
    lines = [
        f"> Provenance: {machine['date']}, {machine['cpu_count']} cores, torch threads {machine['torch_threads']};"
        " `benchmarks/bench_collision.py` (raw: `collision_check.json`).",
        "",
        "# The grasp planner's collision check: points within reach (k-d tree) against every point",
        "",
        "256 grasp frames an object against 1,500 surface samples and its vertices, both checks in one process.",
        "",
        "| meshes | objects | points (mean) | grasps that collide | answers that differ | every point (s) | "
        "within reach (s) | speed-up |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for kind in sorted({r["kind"] for r in rows}):
        sel = [r for r in rows if r["kind"] == kind]
        dense, tree = sum(r["dense_s"] for r in sel), sum(r["tree_s"] for r in sel)
        lines.append(
            f"| {kind} | {len(sel)} | {np.mean([r['points'] for r in sel]):.0f} | "
            f"{sum(r['hits'] for r in sel)} / {256 * len(sel)} | {sum(r['differ'] for r in sel)} | "
            f"{dense:.2f} | {tree:.2f} | x{dense / tree:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--per-category", type=int, default=2)
    parser.add_argument("--meshes", default="", help="glob of predicted labelled meshes (folder name = category)")
    parser.add_argument("--out", type=Path, default=RESULTS / "collision_check")
    args = parser.parse_args()
    gripper, rng, rows = ParallelJawGripper(), np.random.default_rng(0), []
    for folder in sorted(p for p in args.data.iterdir() if p.is_dir()):
        for mesh in sorted(folder.glob("*/mesh.ply"))[: args.per_category]:
            rows.append(
                {
                    "kind": "true (dataset, metric size)",
                    "mesh": mesh.parent.name,
                    **one_object(load(mesh, folder.name), gripper, rng),
                }
            )
            print(rows[-1], flush=True)
    for name in sorted(glob.glob(args.meshes)) if args.meshes else []:
        path = Path(name)
        rows.append(
            {
                "kind": "predicted from one image",
                "mesh": str(path.parent.name),
                **one_object(load(path, path.parent.name), gripper, rng),
            }
        )
        print(rows[-1], flush=True)
    machine = describe_machine()
    args.out.with_suffix(".json").write_text(json.dumps({"machine": machine, "objects": rows}, indent=1) + "\n")
    args.out.with_suffix(".md").write_text(report(rows, machine))
    print(report(rows, machine))


if __name__ == "__main__":
    main()
