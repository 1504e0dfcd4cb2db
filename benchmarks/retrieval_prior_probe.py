"""Probe (issue 12): would AFF-NeRF's labels gain from the nearest training object's true labels as a prior?

Retrieval (the training object whose shape code is nearest, its true labelled mesh) is level with AFF-NeRF in 2D
and ahead in 3D affordance mIoU: it is sharp where the field is blurred. This probe blends the two on the val40
protocol (input view 0 of the seeded order, 5 target views, meshes at 96^3) for several weights w:

- ``image``: per pixel, (1 - w) x AFF-NeRF's rendered class probabilities + w x retrieval's rendered label (one-hot,
  background included);
- ``surface``: AFF-NeRF decides object or background; on the object, its class distribution is blended with the
  label of the retrieved mesh's nearest surface sample to the rendered surface point (the field's depth);
- ``mesh`` (3D metrics): each face of AFF-NeRF's mesh gets argmax of (1 - w) x the field's class probabilities at its
  centre + w x the retrieved mesh's label nearest to it.

Per-object confusion matrices and 3D scores are written, with each object's code distance to its retrieved
object, so gating rules can be read off afterwards.

    OMP_NUM_THREADS=1 python benchmarks/retrieval_prior_probe.py --data DATA --out probe.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch
from scipy.spatial import cKDTree

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.methods.retrieval import RetrievalMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views, object_targets
from affnerf.eval.surface import mesh_samples, sample_seed, true_samples
from affnerf.meshio import LabelledMesh
from affnerf.metrics.segmentation import confusion_matrix, segmentation_metrics
from affnerf.metrics.surface import surface_metrics
from affnerf.model.views import camera_rays, render_view
from affnerf.predict.loading import load_model
from affnerf.predict.mesh import evaluate_points, model_mesh


def blend_image(probs: np.ndarray, retrieved: np.ndarray, w: float) -> np.ndarray:
    """(H, W) labels from (H, W, C) probabilities and (H, W) retrieved labels."""
    onehot = np.eye(probs.shape[-1], dtype=np.float32)[retrieved]
    return ((1 - w) * probs + w * onehot).argmax(-1).astype(np.uint8)


def blend_surface(probs: np.ndarray, transferred: np.ndarray, w: float) -> np.ndarray:
    """(H, W) labels: background where AFF-NeRF's background probability wins over every blended object class;
    ``transferred`` (H, W) retrieved labels at the surface points (0 where there is none)."""
    c = probs.shape[-1]
    obj = probs[..., 1:]
    mass = obj.sum(-1, keepdims=True)
    q = obj / np.maximum(mass, 1e-8)
    has = transferred > 0
    onehot = np.eye(c - 1, dtype=np.float32)[np.clip(transferred - 1, 0, c - 2)]
    q = np.where(has[..., None], (1 - w) * q + w * onehot, q)
    full = np.concatenate([probs[..., :1], mass * q], axis=-1)
    return full.argmax(-1).astype(np.uint8)


def surface_labels(view, intr, pose, tree: cKDTree, labels: np.ndarray) -> np.ndarray:
    """(H, W) retrieved labels at the rendered surface points (0 where the pixel is not opaque)."""
    origins, dirs = camera_rays(intr, pose)
    t = view.depth.reshape(-1)
    points = (origins + dirs * torch.from_numpy(t.astype(np.float64))[:, None]).numpy()
    out = np.zeros(len(t), np.int64)
    hit = t > 0
    if hit.any():
        out[hit] = labels[tree.query(points[hit])[1]]
    return out.reshape(view.depth.shape)


def blended_mesh(mesh: LabelledMesh, probs: np.ndarray, transferred: np.ndarray, w: float) -> LabelledMesh:
    onehot = np.eye(probs.shape[1], dtype=np.float32)[np.clip(transferred - 1, 0, probs.shape[1] - 1)]
    face = ((1 - w) * probs + w * onehot).argmax(1) + 1
    return LabelledMesh(mesh.vertices, mesh.faces, face_props={**mesh.face_props, "affordance": face.astype(np.uint8)})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--run", type=Path, default=Path("src/affnerf/weights/affnerf-small.pt"))
    ap.add_argument("--split", default="val")
    ap.add_argument("--max-objects", type=int, default=5)
    ap.add_argument("--weights", default="0,0.2,0.35,0.5,0.65,0.8,1")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    ws = [float(x) for x in args.weights.split(",")]
    ds = Dataset.open(args.data)
    loaded = load_model(args.run, "cpu")
    model = loaded.model
    nerf = ConditionedNeRFMethod(loaded, mesh_resolution=96)
    started = time.perf_counter()
    retr = RetrievalMethod(loaded, ds, loaded.train_config.get("categories") or None)
    print(f"bank of {len(retr.entries)} in {time.perf_counter() - started:.0f} s", flush=True)
    pconf = ProtocolConfig(input_views=1, target_views=5, scale=0.25, metrics_3d=True)
    c = len(ds.affordance_classes)
    entries = interleave_categories(ds.objects(args.split), args.max_objects)
    rows = []
    for entry in entries:
        obj = ds.load_object(entry)
        inputs, targets = choose_views(len(obj), obj.record.object_id, pconf)
        tset, gt, _ = object_targets(obj, targets, pconf.scale)
        enc = nerf.encoded(obj, inputs)
        grid = nerf.occupancy(obj, inputs)
        near = retr.nearest(obj, inputs)
        code = retr._embed(obj, inputs)
        dist = float(np.sqrt(((retr.bank - code) ** 2).sum(1)).min())
        rmesh = retr.true_mesh(near)
        rs = mesh_samples(rmesh, [0, 1])
        tree = cKDTree(rs.points)
        rimg = retr.predict(obj, inputs, tset).labels
        conf = {f"image_{w}": np.zeros((c, c), np.int64) for w in ws}
        conf.update({f"surface_{w}": np.zeros((c, c), np.int64) for w in ws})
        for k, pose in enumerate(tset.poses):
            view = render_view(model, enc, tset.intrinsics, pose, tset.background, grid=grid)
            sl = surface_labels(view, tset.intrinsics, pose, tree, rs.labels)
            for w in ws:
                conf[f"image_{w}"] += confusion_matrix(gt[k], blend_image(view.affordance, rimg[k], w), c)
                conf[f"surface_{w}"] += confusion_matrix(gt[k], blend_surface(view.affordance, sl, w), c)
        mesh = model_mesh(model, enc, 96, occupancy=grid)
        truth = true_samples(obj, pconf.seed)
        seed = sample_seed(pconf.seed, obj.record.object_id)
        scores = {}
        if len(mesh.faces):
            centres = np.asarray(mesh.vertices, np.float32)[mesh.faces].mean(1)
            probs = evaluate_points(model.point_probabilities(enc), centres)
            transferred = rs.labels[tree.query(centres)[1]]
            for w in ws:
                m = surface_metrics(mesh_samples(blended_mesh(mesh, probs, transferred, w), seed), truth)
                scores[f"mesh_{w}"] = m["affordance_miou_3d"]
        rmetrics = surface_metrics(mesh_samples(rmesh, seed), truth)
        scores["retrieval"] = rmetrics["affordance_miou_3d"]
        rows.append(
            {
                "object": obj.record.object_id,
                "category": obj.record.category,
                "retrieved": near.id,
                "same_category": near.category == obj.record.category,
                "code_distance": dist,
                "confusion": {k: v.tolist() for k, v in conf.items()},
                "retrieval_confusion": sum(confusion_matrix(gt[k], rimg[k], c) for k in range(len(gt))).tolist(),
                "aff3d": scores,
            }
        )
        print(
            obj.record.object_id, near.id, f"{dist:.2f}", {k: round(v or 0, 3) for k, v in scores.items()}, flush=True
        )
    summary = summarise(rows, ws, c)
    args.out.write_text(json.dumps({"summary": summary, "rows": rows, "seconds": time.perf_counter() - started}))
    print(json.dumps(summary, indent=1))


def summarise(rows: list[dict], ws: list[float], c: int) -> dict:
    cats = sorted({r["category"] for r in rows})
    out = {}
    keys = [f"image_{w}" for w in ws] + [f"surface_{w}" for w in ws] + ["retrieval"]
    for key in keys:
        per = []
        for cat in cats:
            field = "retrieval_confusion" if key == "retrieval" else None
            m = sum(np.array(r[field] if field else r["confusion"][key]) for r in rows if r["category"] == cat)
            per.append(segmentation_metrics(m))
        out[key] = {m: float(np.mean([p[m] for p in per])) for m in ("mIoU", "PA", "MPA", "mIoU_object")}
    for key in [f"mesh_{w}" for w in ws] + ["retrieval"]:
        per = []
        for cat in cats:
            vals = [r["aff3d"].get(key) for r in rows if r["category"] == cat]
            vals = [v for v in vals if v is not None]
            per.append(np.mean(vals) if vals else np.nan)
        out[f"aff3d_{key}"] = float(np.nanmean(per))
    out["same_category"] = float(np.mean([r["same_category"] for r in rows]))
    return out


if __name__ == "__main__":
    main()
