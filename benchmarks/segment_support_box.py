"""Does the segmenter's low-probability support give a truer crop box? (issue 16, a probe)

A mask that stops short of a thin tool's tip makes the encoder's crop too small (``segment_crop_box.py``). Here the
segmenter's mask as it ships (:func:`affnerf.model.segmenter.probability_mask`) is joined with every region of its
probability map above a lower threshold ``t`` that touches it, and the bounding box of that union is compared with
the true mask's (box IoU, and the ratio of the longer sides), beside the mask IoU of the union itself, on the
composites of ``bench_segment.py`` (the same seeded draws).

Run::

    .venv/bin/python benchmarks/segment_support_box.py --data /tmp/seg/data --seeds 1 0 \
        --out benchmarks/results/segment_support_box.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy import ndimage

from affnerf.data.crop import object_bbox as bbox
from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict.segment import mask_iou, resolve_segmenter

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402

THRESHOLDS = (0.05, 0.1, 0.2, 0.3)


def box_iou(a, b) -> float:
    """IoU of two boxes (0 when either is None)."""
    if a is None or b is None:
        return 0.0
    ix = max(0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    return inter / ((a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter)


def long_side(box) -> int:
    return 0 if box is None else max(box[2] - box[0], box[3] - box[1])


def with_support(prob: np.ndarray, mask: np.ndarray, t: float) -> np.ndarray:
    """``mask`` joined with the 8-connected regions of ``prob`` > ``t`` that touch it."""
    labels, _ = ndimage.label(prob > t, structure=np.ones((3, 3)))
    touching = np.unique(labels[mask & (labels > 0)])
    return mask | np.isin(labels, touching[touching > 0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 0])
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    model = segnet.load_segmenter(resolve_segmenter(None))
    result = {"machine": describe_machine(), "composites": args.composites, "seeds": {}}
    for seed in args.seeds:
        rows = []
        for c in bench_composites(args.data, seed, args.composites):
            prob = segnet.object_probability(model, c.rgb)
            mask, true_box = segnet.probability_mask(prob), bbox(c.truth)
            row = {"object": c.obj.record.object_id, "background": c.background, "mask_iou": mask_iou(mask, c.truth)}
            row |= {"box_iou": box_iou(bbox(mask), true_box), "side": long_side(bbox(mask)) / long_side(true_box)}
            for t in THRESHOLDS:
                joined = with_support(prob, mask, t)
                row[f"mask_iou_{t}"] = mask_iou(joined, c.truth)
                row[f"box_iou_{t}"] = box_iou(bbox(joined), true_box)
                row[f"side_{t}"] = long_side(bbox(joined)) / long_side(true_box)
            rows.append(row)
        keys = [k for k in rows[0] if k not in ("object", "background")]
        means = {k: round(float(np.mean([r[k] for r in rows])), 4) for k in keys}
        result["seeds"][str(seed)] = {"mean": means, "composites": rows}
        print(seed, json.dumps(means), flush=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
