"""Time to quality (issue 12): how long the current recipe takes to reach the validation mIoU of the model shipped
before the quality work (``affnerf-small`` of 2026-11-23 morning: 20,000 steps, 66 minutes of one core, trained on
a 20-objects-per-category dataset of the same seed).

That model's training objects are objects 0-19 of each category (objects are a pure function of seed, category and
index), so it is scored only on validation objects with index >= 20, which no model here has seen; every other
checkpoint is scored on the same objects: input view 0, ``--views`` target views at ``--scale`` (the ablation
ladder's scorer). A run's checkpoints give its curve against the wall time logged at their steps.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/time_to_quality.py --data DATA --original OLD.pt \\
        --runs RUN... --checkpoints CKPT... --out benchmarks/results/time_to_quality.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from ablation_ladder import curve

from affnerf.data.dataset import Dataset, ObjectData, interleave_categories
from affnerf.environment import describe_machine
from affnerf.predict.loading import load_model
from affnerf.train.validate import validate

#: Objects 0..FIRST_UNSEEN-1 of each category were the original model's dataset.
FIRST_UNSEEN = 20


def unseen_validation(data: Path, per_category: int) -> list[ObjectData]:
    """Validation objects of index >= FIRST_UNSEEN, ``per_category`` of each, round-robin over categories."""
    ds = Dataset.open(data)
    fresh = [e for e in ds.objects("val") if int(e.id.rsplit("_", 1)[1]) >= FIRST_UNSEEN]
    return [ds.load_object(e) for e in interleave_categories(fresh, per_category)]


def score(checkpoint: Path, objects: list[ObjectData], views: int, scale: float) -> dict[str, Any]:
    """2D mIoU and PSNR of one checkpoint on the objects."""
    result = validate(load_model(checkpoint).model.eval(), objects, scale, views_per_object=views)
    return {"checkpoint": str(checkpoint), "mIoU": result.miou, "PSNR": result.psnr}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--original", type=Path, required=True, help="the model shipped before the quality work")
    parser.add_argument("--runs", type=Path, nargs="*", default=[], help="run folders: their checkpoint curves")
    parser.add_argument("--checkpoints", type=Path, nargs="*", default=[], help="single checkpoints to score")
    parser.add_argument("--per-category", type=int, default=2)
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--scale", type=float, default=0.25)
    parser.add_argument("--stride", type=int, default=1)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    objects = unseen_validation(args.data, args.per_category)
    payload: dict[str, Any] = {"machine": describe_machine(), "objects": [o.record.object_id for o in objects]}
    payload["original"] = score(args.original, objects, args.views, args.scale)
    payload["checkpoints"] = [score(c, objects, args.views, args.scale) for c in args.checkpoints]
    payload["runs"] = {str(r): curve(r, objects, args.views, args.scale, args.stride) for r in args.runs}
    args.out.write_text(json.dumps(payload, indent=2) + "\n")
    print(json.dumps(payload, indent=1)[:3000])


if __name__ == "__main__":
    main()
