"""Opacity first, then the part: does deciding a pixel's label in two steps raise the protocol's 2D scores?
(issue 12; benchmarks/results/label_rule.md)

A rendered pixel's distribution puts the light that passes the object on the background (class 0) and the rest on
the parts, so a pixel whose opacity is 0.6, split 0.3 / 0.3 between two parts, is labelled background by the plain
argmax. The two-step rule (:func:`opacity_first_labels`) first calls a pixel object when its opacity reaches
1 − ``threshold`` and then gives it its most likely part. Every target view of the chosen objects is rendered once
(the protocol's seeded input and target views, the fast path as ``affnerf eval`` renders) and labelled both ways.

    .venv/bin/python benchmarks/label_rule.py --data DATA --checkpoint src/affnerf/weights/affnerf-small.pt \
        --out OUT.json [--splits val:5 test:8 --target-views 5 --scale 0.5]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from affnerf.environment import describe_machine
from affnerf.metrics.segmentation import confusion_matrix, segmentation_metrics
from affnerf.vocab import AFFORDANCE_CLASSES

sys.path.insert(0, str(Path(__file__).parent))
from label_bias import CategoryPixels, open_protocol, render_split  # noqa: E402

#: Background probabilities at or above which the two-step rule calls a pixel background (0.5: opacity below 0.5).
THRESHOLDS = (0.3, 0.4, 0.5, 0.6, 0.7)


def opacity_first_labels(log_probs: np.ndarray, threshold: float) -> np.ndarray:
    """(N, C) log-probabilities (class 0 background) -> (N,) labels: 0 where p_0 >= ``threshold``, else the most
    likely of classes 1..C-1.

    Example:
        >>> lp = np.log(np.array([[0.4, 0.3, 0.3], [0.6, 0.1, 0.3]]))
        >>> opacity_first_labels(lp, 0.5).tolist(), lp.argmax(1).tolist()
        ([1, 0], [0, 0])
    """
    p = np.exp(log_probs)
    return np.where(p[:, 0] >= threshold, 0, p[:, 1:].argmax(axis=1) + 1)


def rule_scores(pixels: dict[str, CategoryPixels], decide: Callable[[np.ndarray], np.ndarray]) -> dict:
    """Table 2's segmentation metrics per category and their mean, with labels ``decide(log_probs)``."""
    c = next(iter(pixels.values())).log_probs.shape[1]
    cats = {n: segmentation_metrics(confusion_matrix(p.labels, decide(p.log_probs), c)) for n, p in pixels.items()}
    keys = ("mIoU", "PA", "MPA", "mIoU_object")
    mean = {k: round(float(np.mean([m[k] for m in cats.values()])), 4) for k in keys}
    return {"mean": mean, "categories": {n: round(float(m["mIoU"]), 4) for n, m in cats.items()}}


def class_table(pixels: dict[str, CategoryPixels]) -> dict:
    """Per category, each class present in the truth under the plain argmax: its share of the pixels, IoU,
    recall and precision (where the 2D errors are)."""
    out = {}
    for name, p in pixels.items():
        conf = confusion_matrix(p.labels, p.log_probs.argmax(axis=1), p.log_probs.shape[1]).astype(np.float64)
        truth, found, hit = conf.sum(1), conf.sum(0), np.diag(conf)
        out[name] = {
            AFFORDANCE_CLASSES[k]: {
                "share": round(truth[k] / truth.sum(), 4),
                "iou": round(hit[k] / (truth[k] + found[k] - hit[k]), 3),
                "recall": round(hit[k] / truth[k], 3),
                "precision": round(hit[k] / max(found[k], 1.0), 3),
            }
            for k in np.flatnonzero(truth)
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--checkpoint", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--splits", nargs="+", default=["val:5", "test:8"], help="SPLIT:OBJECTS_PER_CATEGORY")
    parser.add_argument("--target-views", type=int, default=5)
    parser.add_argument("--scale", type=float, default=0.5)
    args = parser.parse_args()
    ds, method, protocol = open_protocol(args)
    result: dict = {"checkpoint": str(args.checkpoint), "machine": describe_machine(), "splits": {}}
    result["protocol"] = {"input_views": 1, "target_views": args.target_views, "scale": args.scale}
    for spec in args.splits:
        split, per_category = spec.split(":")
        start = time.perf_counter()
        pixels = render_split(method, ds, split, int(per_category), protocol)
        rows = {"argmax": rule_scores(pixels, lambda lp: lp.argmax(axis=1))}
        for t in THRESHOLDS:
            rows[f"opacity first, background at p0 >= {t}"] = rule_scores(
                pixels, lambda lp, t=t: opacity_first_labels(lp, t)
            )
        seconds = round(time.perf_counter() - start, 1)
        result["splits"][spec] = {"seconds": seconds, "rules": rows, "classes": class_table(pixels)}
        for name, row in rows.items():
            print(f"{spec:7s} {name:40s} {row['mean']}", flush=True)
    args.out.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
