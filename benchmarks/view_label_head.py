"""How well does the shape encoder's pixel-labelling head label its own crops? (issue 12; results/view_labels.md)

For a run trained with ``--model.view-affordance-weight``: every fifth view of each validation object, its 64-pixel
encoder crop (from the training frame cache) labelled by the head, against the crop's true affordance ids (the
nearest pixel of the cached label map, as training sees them); IoU per class over each category's crops.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/view_label_head.py --checkpoint CKPT --data DATA \
        --cache-dir CACHE [--out OUT.json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset
from affnerf.eval.protocol import per_class_scores
from affnerf.metrics.segmentation import confusion_matrix
from affnerf.predict.loading import load_model
from affnerf.train.cache import cached_frames
from affnerf.train.sampler import crop_maps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkpoint", type=Path, required=True)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--cache-dir", type=Path, required=True)
    parser.add_argument("--split", default="val")
    parser.add_argument("--image-scale", type=float, default=0.25, help="the run's image_scale (small preset: 0.25)")
    parser.add_argument("--every", type=int, default=5, help="label every N-th view of each object")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    torch.set_num_threads(1)
    model = load_model(args.checkpoint, "cpu").model.eval()
    if getattr(model.shape_encoder, "label_head", None) is None:
        raise SystemExit(f"{args.checkpoint}: the model has no pixel-labelling head (--model.view-affordance-weight)")
    ds = Dataset.open(args.data)
    n, size = len(ds.affordance_classes), model.config.encoder_resolution
    conf: dict[str, np.ndarray] = {}
    for entry in ds.objects(args.split):
        frames = cached_frames(ds.load_object(entry), args.cache_dir, args.image_scale, size)
        views = np.arange(0, len(frames), args.every)
        _, labels = crop_maps(frames, views)
        images = torch.from_numpy(np.asarray(frames.crops[views])).permute(0, 3, 1, 2).float() / 255.0
        with torch.no_grad():
            logits = model.shape_encoder.encode(images)[1]
        pred = torch.nn.functional.interpolate(logits, size=(size, size), mode="bilinear").argmax(1).numpy()
        conf.setdefault(entry.category, np.zeros((n, n), np.int64))
        conf[entry.category] += confusion_matrix(labels.reshape(-1), pred.reshape(-1), n)
    names = ds.affordance_classes
    per_class = {c: per_class_scores(m)["IoU_per_class"] for c, m in sorted(conf.items())}
    result = {
        "settings": {k: str(v) for k, v in vars(args).items()},
        "IoU_per_class": {c: {names[i]: v for i, v in enumerate(vs) if v is not None} for c, vs in per_class.items()},
    }
    for c, per in result["IoU_per_class"].items():
        print(c, {k: round(v, 3) for k, v in per.items()})
    if args.out:
        args.out.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
