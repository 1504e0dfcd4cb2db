"""Pilot: does 3D supervision from the training meshes (``--points-weight``) help the ``small`` model in equal time?

Trains the ``small`` preset on one dataset for the same wall-clock minutes per run, one run after the other: with
``points_weight`` 0 (the paper's loss), then with each of ``--weights``. The runs share one cache, built before
any run is timed, so making the point sets costs no run time. Each final checkpoint is then scored on the held-out
instances (splits val and test) with the training validation (:func:`affnerf.train.validate.validate`: input view
0, then ``--views`` targets at ``--scale`` of the dataset's resolution; mIoU with background over all pooled
pixels) and for geometry with the volumetric IoU of OccNet: occupancy (density >= the model's ``surface_density``)
against the truth at the uniform share of each held-out object's point set.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/pilot_points_supervision.py --data /tmp/p3d/data \\
        --work /tmp/p3d/runs --minutes 8 --weights 1.0 0.1 --out benchmarks/results/points_supervision_pilot.json
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import torch
from ablation_ladder import run_parser, warm_cache  # benchmarks/ is the script's folder, first on sys.path

from affnerf.data.dataset import Dataset, ObjectData
from affnerf.environment import describe_machine
from affnerf.model.inputs import dataset_views
from affnerf.predict.loading import load_model
from affnerf.train.cache import cached_points
from affnerf.train.config import SMALL, TrainConfig, config_to_json
from affnerf.train.points import split_counts
from affnerf.train.trainer import train
from affnerf.train.validate import validate


@torch.no_grad()
def volume_iou(model: Any, obj: ObjectData, config: TrainConfig, cache: Path) -> float:
    """Volumetric IoU of the fine field's occupancy from input view 0 on the object's uniform points."""
    sigmas = (config.point_sigma_near, config.point_sigma_far)
    points = cached_points(obj.folder / "mesh.ply", obj.record.object_id, cache, config.model.scene_half_extent, sigmas)
    n = split_counts(len(points), 2)[0]
    crops, intrinsics, poses = dataset_views(obj, [0], model.config)
    encoding = model.encode_views(crops, intrinsics, poses)
    xyz = torch.from_numpy(np.array(points.points[:n]))
    density = model.point_geometry(encoding, torch.zeros(n, dtype=torch.long), xyz)[-1].density
    pred = (density >= model.config.surface_density).numpy()
    truth = np.asarray(points.occupancy[:n]) > 0
    return float((pred & truth).sum() / max((pred | truth).sum(), 1))


def score(run: Path, config: TrainConfig, views: int, scale: float) -> dict[str, Any]:
    """Held-out scores of a run's newest checkpoint, and where its training got to."""
    ds = Dataset.open(config.data)
    objects = [ds.load_object(e) for e in ds.objects("val") + ds.objects("test")]
    model = load_model(run).model.eval()
    result = validate(model, objects, scale, views_per_object=views)
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    summary = json.loads((run / "summary.json").read_text())
    ious = [volume_iou(model, obj, config, Path(config.cache_dir) / "heldout") for obj in objects]
    return {
        "steps": summary["step"],
        "run_seconds": summary["seconds"],
        "last_train_scalars": ([r for r in rows if "loss/mse" in r] or [None])[-1],
        "heldout_objects": len(objects),
        "heldout_mIoU": result.miou,
        "heldout_PSNR": result.psnr,
        "heldout_pixel_accuracy": result.accuracy,
        "heldout_volume_IoU": float(np.mean(ious)),
    }


def main() -> None:
    parser = run_parser(__doc__.splitlines()[0], 8.0)
    parser.add_argument("--weights", type=float, nargs="+", default=[1.0], help="points_weight of the later runs")
    parser.add_argument("--views", type=int, default=4, help="target views per held-out object")
    parser.add_argument("--scale", type=float, default=0.25)
    args = parser.parse_args()
    base = replace(
        SMALL, data=args.data, steps=100_000, time_limit=args.minutes, val_every=0, progress=False, device="cpu"
    )
    base = replace(base, out=args.work / "unused", cache_dir=args.cache or args.work / "cache")
    warm_cache(base)
    results = {}
    for weight in (0.0, *args.weights):
        config = replace(base, out=args.work / f"points_weight_{weight:g}", points_weight=weight)
        train(config)
        scores = score(config.out, config, args.views, args.scale)
        results[f"points_weight_{weight:g}"] = {"config": config_to_json(config), **scores}
        print(json.dumps({k: v for k, v in scores.items() if k != "last_train_scalars"}), flush=True)
    payload = {"machine": describe_machine(), "minutes_each": args.minutes, "runs": results}
    args.out.write_text(json.dumps(payload, indent=2) + "\n")


if __name__ == "__main__":
    main()
