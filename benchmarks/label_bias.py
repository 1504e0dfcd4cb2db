"""Does a per-class label bias, fitted on validation renders, raise the protocol's 2D scores on the test split?
(issue 12; benchmarks/results/label_bias.md)

Renders every target view of the chosen objects once (the protocol's seeded input and target views, the fast
path as ``affnerf eval`` renders), keeps the per-pixel class probabilities, fits the biases on the fit split
(:func:`fit_label_bias`) and scores the score split with biases 0 (the plain argmax,
what ``affnerf eval`` reports without a bias) and with the fitted ones, from the same renders.

    .venv/bin/python benchmarks/label_bias.py --data DATA --checkpoint src/affnerf/weights/affnerf-small.pt \
        --out OUT.json [--fit-per-category 8 --score-per-category 5 --target-views 5 --scale 0.5]
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views, object_targets
from affnerf.metrics.segmentation import confusion_matrix, mean_iou, segmentation_metrics
from affnerf.model.views import render_view
from affnerf.predict.loading import load_model
from affnerf.vocab import AFFORDANCE_CLASSES

#: Candidate biases per class (log weights) of the fit: weights from e^-1.5 = 0.22 to e^1.5 = 4.5.
BIAS_GRID = tuple(round(float(v), 2) for v in np.arange(-1.5, 1.5001, 0.1))
#: Smallest probability the log is taken of (a rendered probability may be exactly 0).
PROBABILITY_FLOOR = 1e-6


@dataclass
class CategoryPixels:
    """Rendered pixels of one category: (N, C) log-probabilities (float32) and (N,) true labels."""

    log_probs: np.ndarray
    labels: np.ndarray


def log_probabilities(probs: np.ndarray) -> np.ndarray:
    """(..., C) probabilities -> float32 log-probabilities, floored at ``PROBABILITY_FLOOR``."""
    return np.log(np.maximum(np.asarray(probs, np.float32), PROBABILITY_FLOOR))


def biased_labels(log_probs: np.ndarray, bias: np.ndarray) -> np.ndarray:
    """(N, C) log-probabilities and (C,) biases -> (N,) labels argmax(log p + b).

    Example:
        >>> lp = np.log(np.array([[0.6, 0.4], [0.9, 0.1]]))
        >>> biased_labels(lp, np.array([0.0, 0.5])).tolist()
        [1, 0]
    """
    return (log_probs + bias[None, :]).argmax(axis=1)


def class_sweep(pixels: CategoryPixels, bias: np.ndarray, k: int, values: np.ndarray) -> np.ndarray:
    """(V, C, C) confusion matrices of ``pixels`` with class ``k``'s bias set to each of the (V,) ascending
    ``values`` (the other classes keep ``bias``): a pixel takes k exactly when b_k exceeds its own threshold (the
    best other score minus log p_k), so one bincount over the thresholds' places in ``values`` gives them all.

    Example:
        >>> px = CategoryPixels(np.log(np.array([[0.6, 0.4], [0.9, 0.1]])), np.array([1, 0]))
        >>> [c.tolist() for c in class_sweep(px, np.zeros(2), 1, np.array([0.0, 0.5, 3.0]))]
        [[[1, 0], [1, 0]], [[1, 0], [0, 1]], [[0, 1], [0, 1]]]
    """
    c = pixels.log_probs.shape[1]
    scores = pixels.log_probs + bias[None, :]
    scores[:, k] = -np.inf
    other = scores.argmax(axis=1)
    threshold = scores[np.arange(len(other)), other] - pixels.log_probs[:, k]
    first = np.searchsorted(values, threshold, side="right")  # the first value strictly above the threshold
    gt = pixels.labels.astype(np.int64)
    base = confusion_matrix(gt, other, c)
    moved = np.bincount((first * c + gt) * c + other, minlength=(len(values) + 1) * c * c)
    moved = np.cumsum(moved.reshape(len(values) + 1, c, c)[: len(values)], axis=0)
    out = base[None] - moved
    out[:, :, k] += moved.sum(axis=2)
    return out


def mean_category_miou(confusions: list[np.ndarray]) -> float:
    """The protocol's headline: per-category mIoU (classes present in its ground truth) averaged."""
    return float(np.mean([mean_iou(conf) for conf in confusions]))


def objective_now(pixels: list[CategoryPixels], bias: np.ndarray) -> float:
    """The mean category mIoU of ``pixels`` with labels decided by ``bias``."""
    c = len(bias)
    return mean_category_miou([confusion_matrix(p.labels, biased_labels(p.log_probs, bias), c) for p in pixels])


def fit_label_bias(pixels: list[CategoryPixels], passes: int = 3) -> tuple[np.ndarray, list[float]]:
    """Coordinate ascent of the (C,) biases (background fixed at 0) on the mean category mIoU: each pass sets
    classes 1..C-1 in turn to the grid value with the best objective (ties: nearest 0); stops when a pass changes
    nothing. Returns the biases and the objective before the first pass and after each."""
    values = np.asarray(BIAS_GRID, np.float64)
    bias = np.zeros(pixels[0].log_probs.shape[1])
    history = [objective_now(pixels, bias)]
    for _ in range(passes):
        changed = False
        for k in range(1, len(bias)):
            sweeps = [class_sweep(p, bias, k, values) for p in pixels]
            objective = np.array([mean_category_miou([s[i] for s in sweeps]) for i in range(len(values))])
            best = np.flatnonzero(objective >= objective.max() - 1e-12)
            pick = values[best[np.argmin(np.abs(values[best]))]]
            if pick != bias[k] and objective.max() > objective[np.isclose(values, bias[k])].max(initial=-1.0):
                bias[k], changed = pick, True
        history.append(objective_now(pixels, bias))
        if not changed:
            break
    return bias, history


def render_split(method: ConditionedNeRFMethod, ds: Dataset, split: str, per_category: int, protocol: ProtocolConfig):
    """Per category, the rendered log-probabilities and true labels of every target pixel of its objects."""
    found: dict[str, tuple[list[np.ndarray], list[np.ndarray]]] = {}
    for entry in interleave_categories(ds.objects(split), per_category):
        obj = ds.load_object(entry)
        inputs, targets = choose_views(len(obj), obj.record.object_id, protocol)
        target_set, gt, _ = object_targets(obj, targets, protocol.scale)
        encoding, grid = method.encoded(obj, inputs), method.occupancy(obj, inputs)
        for pose, truth in zip(target_set.poses, gt, strict=True):
            view = render_view(
                method.loaded.model, encoding, target_set.intrinsics, pose, target_set.background, method.chunk, grid
            )
            lp, lab = found.setdefault(entry.category, ([], []))
            lp.append(log_probabilities(view.affordance).reshape(-1, view.affordance.shape[-1]))
            lab.append(truth.reshape(-1))
    return {c: CategoryPixels(np.concatenate(lp), np.concatenate(lab)) for c, (lp, lab) in sorted(found.items())}


def scores(pixels: dict[str, CategoryPixels], bias: np.ndarray) -> dict:
    """Table 2's segmentation metrics per category and their mean, deciding labels with ``bias``."""
    c = len(bias)
    cats = {
        name: segmentation_metrics(confusion_matrix(p.labels, biased_labels(p.log_probs, bias), c))
        for name, p in pixels.items()
    }
    keys = ("mIoU", "PA", "MPA", "mIoU_object")
    mean = {k: float(np.mean([m[k] for m in cats.values()])) for k in keys}
    return {"mean": mean, "categories": {n: {k: m[k] for k in keys} for n, m in cats.items()}}


def open_protocol(args: argparse.Namespace) -> tuple[Dataset, ConditionedNeRFMethod, ProtocolConfig]:
    """The dataset, the model and the one-input-view protocol of ``args.data``, ``args.checkpoint``,
    ``args.target_views`` and ``args.scale`` (also ``label_rule.py``'s)."""
    method = ConditionedNeRFMethod(load_model(args.checkpoint, "cpu"))
    protocol = ProtocolConfig(input_views=1, target_views=args.target_views, scale=args.scale)
    return Dataset.open(args.data), method, protocol


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--checkpoint", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--fit-split", default="val")
    parser.add_argument("--fit-per-category", type=int, default=8)
    parser.add_argument("--score-split", default="test")
    parser.add_argument("--score-per-category", type=int, default=5)
    parser.add_argument("--target-views", type=int, default=5)
    parser.add_argument("--scale", type=float, default=0.5)
    args = parser.parse_args()
    ds, method, protocol = open_protocol(args)
    start = time.perf_counter()
    fit_pixels = render_split(method, ds, args.fit_split, args.fit_per_category, protocol)
    score_pixels = render_split(method, ds, args.score_split, args.score_per_category, protocol)
    rendered = time.perf_counter() - start
    bias, history = fit_label_bias(list(fit_pixels.values()))
    fitted = time.perf_counter() - start - rendered
    zero = np.zeros_like(bias)
    result = {
        "checkpoint": str(args.checkpoint),
        "protocol": {"input_views": 1, "target_views": args.target_views, "scale": args.scale},
        "fit": {"split": args.fit_split, "per_category": args.fit_per_category, "objective_by_pass": history},
        "bias": {name: float(b) for name, b in zip(AFFORDANCE_CLASSES, bias, strict=True)},
        "seconds": {"render": rendered, "fit": fitted},
        args.fit_split: {"plain": scores(fit_pixels, zero), "biased": scores(fit_pixels, bias)},
        args.score_split: {"plain": scores(score_pixels, zero), "biased": scores(score_pixels, bias)},
    }
    args.out.write_text(json.dumps(result, indent=1))
    for split in (args.fit_split, args.score_split):
        for kind in ("plain", "biased"):
            m = result[split][kind]["mean"]
            print(f"{split:5s} {kind:6s} mIoU {m['mIoU']:.4f} PA {m['PA']:.4f} MPA {m['MPA']:.4f}")
    print("bias", {k: v for k, v in result["bias"].items() if v}, f"render {rendered:.0f}s fit {fitted:.0f}s")


if __name__ == "__main__":
    main()
