"""What the 3D metrics' outer-surface rule changes (conventions §5): a model's meshes scored against every sample of
the true ``mesh.ply`` (the rule before 2026-11-28) and against its outer-surface samples only (the rule since), on
the first ``--per-category`` validation objects of each category, predicted from view 0 with the encoders' codes.

Run::

    .venv/bin/python benchmarks/outer_surface_metric.py --data DATA --run src/affnerf/weights/affnerf-small.pt \
        --out benchmarks/results/outer_surface_metric.json

where DATA is ``affnerf data generate --objects-per-category 80 --views 30 --seed 0``.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
import torch
from PIL import Image

from affnerf.data.dataset import Dataset
from affnerf.environment import describe_machine
from affnerf.eval.surface import mesh_samples, sample_seed
from affnerf.meshio import read_labelled_ply
from affnerf.metrics.surface import sample_surface, surface_metrics
from affnerf.predict.predictor import Predictor


def object_row(predictor: Predictor, obj, tmp: Path) -> dict:
    """One object's F@1cm and 3D affordance mIoU under both rules, and the share of its true samples hidden."""
    truth_mesh = read_labelled_ply(obj.folder / "mesh.ply")
    seed = sample_seed(0, obj.record.object_id)
    labels = truth_mesh.face_props["affordance"]
    every = sample_surface(truth_mesh.vertices, truth_mesh.faces, labels, rng=np.random.default_rng(seed + [1]))
    outer = mesh_samples(truth_mesh, seed + [1])
    photo = tmp / f"{obj.record.object_id}.png"
    Image.fromarray(obj.rgb(0)).save(photo)
    predicted = mesh_samples(predictor.mesh(predictor.encode_image(photo), 96), seed)
    old, new = surface_metrics(predicted, every), surface_metrics(predicted, outer)
    row = {"object": obj.record.object_id, "hidden_share": round(1 - len(outer) / len(every), 4)}
    for key in ("fscore_1cm", "affordance_miou_3d"):
        row[f"{key} every sample"], row[f"{key} outer surface"] = round(old[key], 4), round(new[key], 4)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--run", type=Path, default=Path("src/affnerf/weights/affnerf-small.pt"))
    parser.add_argument("--per-category", type=int, default=2)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    torch.set_num_threads(1)
    predictor = Predictor.load(args.run, "cpu")
    ds = Dataset.open(args.data)
    entries = ds.objects("val")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for cat in sorted({e.category for e in entries}):
            for entry in [e for e in entries if e.category == cat][: args.per_category]:
                rows.append(object_row(predictor, ds.load_object(entry), Path(tmp)))
                print(rows[-1], flush=True)
    keys = [k for k in rows[0] if k != "object"]
    mean = {k: round(float(np.mean([r[k] for r in rows])), 4) for k in keys}
    out = {"run": str(args.run), "objects": len(rows), "mean": mean, "rows": rows, "machine": describe_machine()}
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(mean))


if __name__ == "__main__":
    main()
