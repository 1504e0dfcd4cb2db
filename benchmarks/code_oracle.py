"""How good can the decoder be with the best codes? (issue 12, results/code_oracle*.md)

This separates the two halves of the model (results: ``code_oracle.md`` for the model of 2026-11-25, when every
lever on the network's size and loss left it level, and ``code_oracle_shipped.md`` for the weights shipped since
2026-12-05): for each object the codes are fitted, with the weights
frozen, to K posed views of it (Adam on the shape and appearance codes, the training loss: colour MSE + λ CE on
coarse and fine stages) and then scored at the protocol's target views, which the fit never sees, beside the
encoder's codes from the one input view. If the fitted codes score far higher, the decoder can express the object
and the single image (the encoder, or what one view tells) is the limit; if not, the decoder is.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/code_oracle.py --data DATA --split val --out OUT.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset, ObjectData, interleave_categories
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views, object_targets, per_class_scores, view_order
from affnerf.metrics.segmentation import confusion_matrix, segmentation_metrics
from affnerf.model.affnerf import Codes
from affnerf.model.views import camera_rays, render_view
from affnerf.predict.loading import load_model
from affnerf.train.loss import nerf_loss


def view_rays(obj: ObjectData, views: list[int], scale: float) -> tuple[torch.Tensor, ...]:
    """Every pixel of ``views`` at ``scale``: origins (R, 3), directions (R, 3), colours (R, 3), labels (R,)."""
    target_set, labels, rgb = object_targets(obj, views, scale)
    rays = [camera_rays(target_set.intrinsics, pose) for pose in target_set.poses]
    origins = torch.cat([o for o, _ in rays]).float()
    dirs = torch.cat([d for _, d in rays]).float()
    colours = torch.from_numpy(rgb.reshape(-1, 3).astype(np.float32) / 255.0)
    return origins, dirs, colours, torch.from_numpy(labels.reshape(-1).astype(np.int64))


def fit_to_views(method: ConditionedNeRFMethod, codes: Codes, rays: tuple[torch.Tensor, ...], args) -> Codes:
    """The codes after ``args.steps`` Adam steps on ``args.rays`` random rays of the fit views (weights frozen)."""
    model = method.loaded.model
    origins, dirs, colours, labels = rays
    shape = codes.shape.detach().clone().requires_grad_(True)
    appearance = codes.appearance.detach().clone().requires_grad_(True)
    optim = torch.optim.Adam([shape, appearance], lr=args.lr)
    generator = torch.Generator().manual_seed(0)
    background = torch.tensor(method.loaded.background, dtype=torch.float32).expand(args.rays, 3)
    for _ in range(args.steps):
        pick = torch.randperm(len(origins), generator=generator)[: args.rays]
        obj = torch.zeros(len(pick), dtype=torch.long)
        coarse, fine = model.render_rays(Codes(shape, appearance), obj, origins[pick], dirs[pick], background)
        loss = nerf_loss(coarse, fine, colours[pick], labels[pick], args.affordance_weight).total
        optim.zero_grad(set_to_none=True)
        loss.backward()
        optim.step()
    return Codes(shape.detach(), appearance.detach())


def target_labels(method: ConditionedNeRFMethod, codes: Codes, obj: ObjectData, targets: list[int], scale: float):
    """(K, H, W) rendered labels of ``codes`` at the target views, and the truth there."""
    target_set, gt, _ = object_targets(obj, targets, scale)
    grid = method.loaded.model.occupancy(codes)
    views = [
        render_view(method.loaded.model, codes, target_set.intrinsics, pose, target_set.background, grid=grid)
        for pose in target_set.poses
    ]
    return np.stack([v.labels for v in views]), gt


def category_mious(cats: dict[str, np.ndarray]) -> dict:
    """Per-category (C, C) confusion matrices -> {"mIoU": the mean over categories, "per_category": each one's}."""
    per = {c: segmentation_metrics(m)["mIoU"] for c, m in sorted(cats.items())}
    return {"mIoU": float(np.mean(list(per.values()))), "per_category": per}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--checkpoint", type=Path, default=Path("src/affnerf/weights/affnerf-small.pt"))
    parser.add_argument("--split", default="val")
    parser.add_argument("--categories", default="", help="comma-separated categories (default: all)")
    parser.add_argument("--per-category", type=int, default=2)
    parser.add_argument("--fit-views", type=int, default=10)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--rays", type=int, default=1024)
    parser.add_argument("--lr", type=float, default=0.05)
    parser.add_argument("--affordance-weight", type=float, default=4e-2)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    torch.set_num_threads(1)
    loaded = load_model(args.checkpoint, "cpu")
    loaded.model.eval()
    method = ConditionedNeRFMethod(loaded)
    dataset = Dataset.open(args.data)
    protocol = ProtocolConfig(target_views=5, scale=0.25)
    n = len(dataset.affordance_classes)
    conf: dict[str, dict[str, np.ndarray]] = {"encoder": {}, "fitted": {}}
    start = time.perf_counter()
    wanted = set(filter(None, args.categories.split(",")))
    entries = [e for e in dataset.objects(args.split) if not wanted or e.category in wanted]
    for entry in interleave_categories(entries, args.per_category):
        obj = dataset.load_object(entry)
        inputs, targets = choose_views(len(obj), entry.id, protocol)
        fit_views = [v for v in view_order(len(obj), entry.id, 1) if v not in inputs + targets][: args.fit_views]
        with torch.no_grad():
            codes = method.encode(obj, inputs)
        fitted = fit_to_views(method, codes, view_rays(obj, fit_views, protocol.scale), args)
        for name, c in (("encoder", codes), ("fitted", fitted)):
            pred, gt = target_labels(method, c, obj, targets, protocol.scale)
            cat = conf[name].setdefault(entry.category, np.zeros((n, n), np.int64))
            cat += confusion_matrix(gt, pred, n)
        print(entry.id, f"{time.perf_counter() - start:.0f} s", flush=True)
    result = {"settings": {k: str(v) for k, v in vars(args).items()}, "seconds": time.perf_counter() - start}
    for name, cats in conf.items():
        result[name] = {
            **category_mious(cats),
            "IoU_per_class": {c: per_class_scores(m)["IoU_per_class"] for c, m in sorted(cats.items())},
        }
        per = result[name]["per_category"]
        print(name, round(result[name]["mIoU"], 3), {c: round(v, 3) for c, v in per.items()})
    args.out.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
