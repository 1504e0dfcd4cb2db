"""What are pixel-aligned features worth with a right camera? (issue 12)

The pose-aware model (``--model.kind pose-aware``) reads the input image's features where each query point
projects, through an input camera it must find itself; trained with its own camera head it lost to AFF-NeRF
(``results/pose_aware.md``), its camera 11-24 degrees off. This scores a pose-aware run trained with the true input
cameras (``--model.projection-camera given``, an oracle) on validation objects, projecting with:

- ``true``: the input view's true camera (the oracle's ceiling; not available from a photo);
- ``azD`` / ``elD``: the true camera turned D degrees in azimuth (about the canonical z axis) or raised D degrees
  in elevation, both about the canonical origin (how fast the ceiling falls with a camera error);
- ``fit``: the camera that the shipped model's fit to the photo finds (``affnerf predict``'s, from the input crop and
  its intrinsics only; ``results/fit_camera_accuracy.md``): what a photo would get today;
- ``head``: the run's own camera head.

Beside it, any number of ``--reference`` runs (AFF-NeRF's global codes) scored on the same objects and views.
Protocol: the first ``--per-category`` validation objects of each category, input view 0, ``--views`` target views
spread over the rest (as training's validation), at ``--scale`` of the dataset's resolution; mIoU pooled over all
pixels (classes present in the ground truth), PSNR, and the mesh at ``--resolution``^3 (the model's surface
density) scored by F@1cm and 3D affordance mIoU.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/pose_oracle.py --data DATA --run ORACLE_RUN \\
        --cameras true,az10,el10,fit,head [--reference RUN ...] --out OUT.json
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset, ObjectData, interleave_categories
from affnerf.environment import describe_machine
from affnerf.eval.protocol import resized
from affnerf.eval.surface import sample_seed, score_mesh, true_samples
from affnerf.fileio import write_json_atomic
from affnerf.metrics.image import psnr
from affnerf.metrics.segmentation import confusion_matrix, mean_iou
from affnerf.model.base import ConditionedNeRF
from affnerf.model.inputs import dataset_views
from affnerf.model.views import render_view
from affnerf.objects.primitives import rotation
from affnerf.predict.invert import InversionConfig, dataset_crop_target, invert
from affnerf.predict.loading import LoadedModel, load_model
from affnerf.predict.mesh import model_mesh
from affnerf.predict.shipped import shipped_model

#: (1, 1, 4, 4) camera-to-canonical pose of an object's input view, from the view's true pose.
CameraRule = Callable[[ObjectData, torch.Tensor], torch.Tensor]


def turned(c2w: np.ndarray, azimuth: float = 0.0, elevation: float = 0.0) -> np.ndarray:
    """(4, 4) camera-to-canonical pose moved about the canonical origin: turned ``azimuth`` degrees about +z, then
    raised ``elevation`` degrees (towards +z) about the horizontal axis perpendicular to its eye direction."""
    turn = rotation((0.0, 0.0, 1.0), math.radians(azimuth))
    side = np.cross(turn[:3, :3] @ c2w[:3, 3], [0.0, 0.0, 1.0])
    return rotation(side, math.radians(elevation)) @ turn @ c2w


def fit_rule(shipped: LoadedModel) -> CameraRule:
    """The camera the shipped model's fit to the input crop finds (``affnerf predict``'s defaults; never the pose)."""
    model = shipped.model.eval()

    def rule(obj: ObjectData, poses: torch.Tensor) -> torch.Tensor:
        size = model.config.encoder_resolution
        images, intr, true = dataset_views(obj, [0], model.config)
        with torch.no_grad():
            codes = model.encode_views(images, intr, true)
        target = dataset_crop_target(obj, 0, size)
        with torch.enable_grad():  # the scorer runs without gradients; the fit needs them
            found = invert(model, codes, target, np.asarray(shipped.background), InversionConfig())
        return torch.from_numpy(found.camera_to_world()).float()[None, None]

    return rule


def camera_rule(name: str, shipped: Callable[[], LoadedModel]) -> CameraRule:
    """The rule a ``--cameras`` name stands for (``head`` projects with the true pose given, see :func:`score`)."""
    if name in ("true", "head"):
        return lambda obj, poses: poses
    if name == "fit":
        return fit_rule(shipped())
    kind, degrees = name[:2], float(name[2:])
    if kind not in ("az", "el"):
        raise SystemExit(f"--cameras: unknown camera {name!r} (true, fit, head, azD, elD)")
    key = "azimuth" if kind == "az" else "elevation"
    return lambda obj, poses: torch.from_numpy(turned(poses[0, 0].double().numpy(), **{key: degrees})).float()[
        None, None
    ]


@torch.no_grad()
def score(
    model: ConditionedNeRF, objects: list[ObjectData], rule: CameraRule, args: argparse.Namespace
) -> dict[str, float]:
    """2D and 3D scores of ``model`` encoding each object's view 0 with the pose ``rule`` gives."""
    conf = np.zeros((model.num_classes, model.num_classes), np.int64)
    psnrs, fscores, labels3d = [], [], []
    for obj in objects:
        crops, intrinsics, poses = dataset_views(obj, [0], model.config)
        encoding = model.encode_views(crops, intrinsics, rule(obj, poses))
        intr = obj.record.intrinsics.scaled(args.scale)
        for view in np.linspace(1, len(obj) - 1, args.views).round().astype(int):
            out = render_view(model, encoding, intr, obj.pose(int(view)), obj.record.background_color)
            size = (intr.width, intr.height)
            psnrs.append(psnr(out.rgb, resized(obj.rgb(int(view)), size, nearest=False) / 255.0))
            conf += confusion_matrix(resized(obj.affordance(int(view)), size, nearest=True), out.labels, len(conf))
        mesh = model_mesh(model, encoding, args.resolution)
        result = score_mesh(mesh if len(mesh.faces) else None, true_samples(obj, 0), sample_seed(0, "oracle"))
        fscores.append(0.0 if result is None else result["fscore_1cm"])
        labels3d.append(0.0 if result is None or result["affordance_miou_3d"] is None else result["affordance_miou_3d"])
    return {
        "mIoU": round(mean_iou(conf), 4),
        "PSNR": round(float(np.mean(psnrs)), 3),
        "fscore_1cm": round(float(np.mean(fscores)), 4),
        "affordance_miou_3d": round(float(np.mean(labels3d)), 4),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--run", type=Path, default=None, help="pose-aware run trained with the true cameras")
    parser.add_argument("--cameras", default="true,az10,el10,fit,head")
    parser.add_argument("--reference", type=Path, nargs="*", default=[], help="AFF-NeRF runs scored beside it")
    parser.add_argument("--per-category", type=int, default=5)
    parser.add_argument("--views", type=int, default=5)
    parser.add_argument("--scale", type=float, default=0.25)
    parser.add_argument("--resolution", type=int, default=64)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    started = time.perf_counter()
    ds = Dataset.open(args.data)
    objects = [ds.load_object(e) for e in interleave_categories(ds.objects("val"), args.per_category)]
    rows: dict[str, dict[str, float]] = {}
    for ref in args.reference:
        rows[f"reference {ref}"] = score(
            load_model(ref).model.eval(), objects, camera_rule("true", shipped_model), args
        )
        print(ref, rows[f"reference {ref}"], flush=True)
    if args.run is not None:
        loaded = load_model(args.run)
        for name in args.cameras.split(","):
            projection = "predicted" if name == "head" else "given"
            model = loaded.model.eval()
            model.config = replace(model.config, projection_camera=projection)
            rule = camera_rule(name, lambda: load_model(shipped_model()))
            rows[name] = score(model, objects, rule, args)
            print(name, rows[name], flush=True)
    payload = {
        "benchmark": "pose_oracle",
        "settings": {k: str(v) for k, v in vars(args).items()},
        "objects": len(objects),
        "machine": describe_machine(),
        "seconds": round(time.perf_counter() - started, 1),
        "rows": rows,
    }
    write_json_atomic(args.out, payload)
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
