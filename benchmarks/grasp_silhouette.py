"""Restricted grasps on predicted meshes kept to faces inside the photo's silhouette (issue 13): a probe.

A grasp whose contacts lie on matter the model made up (a scissors' ring filled in, a blob beside an eyeglass rim)
closes on nothing on the true object. Matter the photo shows as background cannot be there, so this plans Table 3's
"predicted from one image, predicted task part" condition (``affnerf eval grasp``'s code: the fitted prediction,
its mesh confirmed by the encoder's own, the planner's tiers) with the confirmed faces further limited to those
whose centre projects, at the camera the fit found, within TOL pixels of the input view's mask (a 128-pixel crop),
and scores the grasps on the true mesh. Also the largest distance from the mask of each grasp's two contacts
(planned as shipped), to see whether it tells the grasps that miss from those that hit.

Run (5 objects per category of the split)::

    .venv/bin/python benchmarks/grasp_silhouette.py --data DATA --split val --categories scissors,eyeglasses \
        --out a.json
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.ndimage import distance_transform_edt

from affnerf.data.dataset import Dataset, ObjectData
from affnerf.eval.grasp_table import task_affordance
from affnerf.eval.grasps import GraspEvalConfig, _plan, condition_settings, object_size
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.planner import PlanConfig
from affnerf.grasp.scoring import score_grasps
from affnerf.grasp.size import scaled
from affnerf.grasp.target import GraspObject
from affnerf.meshio import read_labelled_ply
from affnerf.model.inputs import dataset_views
from affnerf.predict.agreement import confirmed
from affnerf.predict.invert import CropTarget, InversionConfig, dataset_crop_target, invert
from affnerf.predict.loading import load_model
from affnerf.predict.mesh import model_mesh
from affnerf.predict.viewpoint import project_points

TOLERANCES = (0.5, 1.5, 3.0)


def pixels_off_mask(
    points: np.ndarray, camera: tuple[float, float, float], target: CropTarget, gap: np.ndarray
) -> np.ndarray:
    """(P,) distance in pixels from the crop's mask of each canonical point (P, 3) seen from ``camera`` (azimuth,
    elevation, distance, looking at the origin), read from ``gap`` (S, S), the mask's distance transform
    (:func:`mask_gap`); 99 outside the crop."""
    u, v, front = (a[0] for a in project_points(points, np.asarray([camera], float), np.asarray(target.intrinsics)))
    side = target.mask.shape[0]
    inside = (u >= 0) & (u < side) & (v >= 0) & (v < side) & front
    ui, vi = np.clip(u.astype(int), 0, side - 1), np.clip(v.astype(int), 0, side - 1)
    return np.where(inside, gap[vi, ui], 99.0)


def mask_gap(target: CropTarget) -> np.ndarray:
    """(S, S) distance in pixels of each crop pixel from the crop's mask (0 on it)."""
    return distance_transform_edt(target.mask < 0.5)


def probe_object(loaded, obj: ObjectData, config: GraspEvalConfig) -> dict:
    """Each variant's grasps on one object: on the true part or not, and their contacts' distance from the mask."""
    model = loaded.model
    view = choose_views(len(obj), obj.record.object_id, ProtocolConfig(input_views=1, target_views=0, seed=0))[0][0]
    first = model.encode_views(*dataset_views(obj, [view], model.config))
    target = dataset_crop_target(obj, view, model.config)
    fit = invert(model, first, target, np.asarray(loaded.background), InversionConfig(steps=30, seed=view))
    mesh = model_mesh(model, fit.codes, 128, None, model.occupancy(fit.codes))
    mesh = confirmed(mesh, model_mesh(model, first, 128, None, model.occupancy(first)))
    big = dataset_crop_target(obj, view, 128)
    gap = mask_gap(big)
    face_gap = pixels_off_mask(mesh.vertices[mesh.faces].mean(axis=1), fit.camera, big, gap)
    canonical = GraspObject.from_mesh(read_labelled_ply(obj.folder / "mesh.ply"), obj.record.object_id)
    size, task = object_size(obj, canonical, config), task_affordance(obj.record.category)
    truth = scaled(canonical, size.factor)
    settings = condition_settings(PlanConfig(num=16, seed=0, part_margin=0.01), "predicted", task, config)
    out = {"object": obj.record.object_id, "category": obj.record.category, "variants": {}}
    for name, tol in [("shipped", None)] + [(f"within {t} px", t) for t in TOLERANCES]:
        agrees = mesh.face_props["confirmed"].astype(bool) & (face_gap <= (np.inf if tol is None else tol))
        props = {**mesh.face_props, "confirmed": agrees.astype(np.uint8)}
        planning = scaled(GraspObject.from_mesh(replace(mesh, face_props=props)), size.factor)
        grasps, _ = _plan(planning, settings, ParallelJawGripper(), size.source)
        scores = score_grasps(truth, np.stack([g.pose for g in grasps]) if grasps else np.zeros((0, 4, 4)))
        gaps = [float(pixels_off_mask(g.contacts / size.factor, fit.camera, big, gap).max()) for g in grasps]
        out["variants"][name] = {"on_part": [s.on(task) for s in scores], "contact_pixels_off_mask": gaps}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--split", default="val")
    parser.add_argument("--categories", default="scissors,eyeglasses,pen,teapot")
    parser.add_argument("--run", type=Path, default=Path("src/affnerf/weights/affnerf-small.pt"))
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    loaded, ds = load_model(args.run, "cpu"), Dataset.open(args.data)
    config = GraspEvalConfig(run=str(args.run), data=str(args.data), out=str(args.out.parent))
    rows = []
    for category in args.categories.split(","):
        for entry in ds.objects(args.split, [category])[:5]:
            rows.append(probe_object(loaded, ds.load_object(entry), config))
            shares = {k: f"{sum(v['on_part'])}/{len(v['on_part'])}" for k, v in rows[-1]["variants"].items()}
            print(rows[-1]["object"], shares, flush=True)
            args.out.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
