"""How the rendered outline compares with the true one (issue 12, results/fine_tune_losses.md).

For each checkpoint: 2 validation objects per category, the protocol's seeded input view and 3 target views at
100×75; the rendered opacity > 0.5 against the true object mask, pooled over all pixels: mask IoU, the predicted
area over the true area, and the mean opacity on background and on object pixels.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/silhouette_area.py --data DATA CKPT [CKPT ...]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views, object_targets
from affnerf.model.views import render_view
from affnerf.predict.loading import load_model


def silhouette_scores(checkpoint: Path, dataset: Dataset, per_category: int, config: ProtocolConfig) -> dict:
    """Pooled outline scores of one checkpoint on the first ``per_category`` validation objects of each family."""
    loaded = load_model(checkpoint, "cpu")
    loaded.model.eval()
    method = ConditionedNeRFMethod(loaded)
    inter = union = predicted = true = 0
    bg_opacity, obj_opacity = [], []
    for entry in interleave_categories(dataset.objects("val"), per_category):
        obj = dataset.load_object(entry)
        inputs, targets = choose_views(len(obj), entry.id, config)
        target_set, gt, _ = object_targets(obj, targets, config.scale)
        codes, grid = method.encoded(obj, inputs), method.occupancy(obj, inputs)
        for pose, labels in zip(target_set.poses, gt, strict=True):
            view = render_view(loaded.model, codes, target_set.intrinsics, pose, target_set.background, grid=grid)
            ours, theirs = view.opacity > 0.5, labels > 0
            inter += int((ours & theirs).sum())
            union += int((ours | theirs).sum())
            predicted += int(ours.sum())
            true += int(theirs.sum())
            bg_opacity.append(float(view.opacity[~theirs].mean()))
            obj_opacity.append(float(view.opacity[theirs].mean()))
    return {
        "mask_iou": inter / union,
        "area_ratio": predicted / true,
        "opacity_background": float(np.mean(bg_opacity)),
        "opacity_object": float(np.mean(obj_opacity)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--per-category", type=int, default=2)
    parser.add_argument("checkpoints", type=Path, nargs="+")
    args = parser.parse_args()
    torch.set_num_threads(1)
    dataset = Dataset.open(args.data)
    config = ProtocolConfig(target_views=3, scale=0.25)
    scores = {str(c): silhouette_scores(c, dataset, args.per_category, config) for c in args.checkpoints}
    print(json.dumps(scores, indent=1))


if __name__ == "__main__":
    main()
