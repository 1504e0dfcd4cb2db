"""Segmentation metrics on confusion matrices (conventions §5), as in Semantic-NeRF's ``miou_valid_class``.

Per category one confusion matrix accumulates all target views; the classes counted are those present in its
ground truth. IoU_c = TP / (TP + FP + FN); mIoU averages IoU over those classes; PA = correct / all pixels;
MPA averages TP / (TP + FN) over those classes. The object-only variant keeps only pixels whose ground truth is
not background, and does not count the background class.
"""

from __future__ import annotations

import math

import numpy as np


def confusion_matrix(gt: np.ndarray, pred: np.ndarray, num_classes: int) -> np.ndarray:
    """(C, C) int64 counts: row = ground-truth class, column = predicted class.

    Args:
        gt: integer labels of any shape.
        pred: integer labels of the same shape.
        num_classes: C; labels must lie in [0, C).

    Example:
        >>> confusion_matrix(np.array([0, 1, 1]), np.array([0, 1, 0]), 2).tolist()
        [[1, 0], [1, 1]]
    """
    gt = np.asarray(gt, np.int64).reshape(-1)
    pred = np.asarray(pred, np.int64).reshape(-1)
    if gt.shape != pred.shape:
        raise ValueError(f"ground truth has {gt.size} labels, prediction {pred.size}")
    if gt.size and (min(gt.min(), pred.min()) < 0 or max(gt.max(), pred.max()) >= num_classes):
        raise ValueError(f"labels outside [0, {num_classes})")
    return np.bincount(gt * num_classes + pred, minlength=num_classes * num_classes).reshape(num_classes, num_classes)


def object_only(conf: np.ndarray) -> np.ndarray:
    """The confusion matrix restricted to pixels whose ground truth is not background (row 0 removed).

    Predictions of background on object pixels stay counted (as misses); the background class itself is then
    not among the classes averaged, since no ground truth of it remains.
    """
    out = conf.copy()
    out[0, :] = 0
    return out


def present_classes(conf: np.ndarray) -> np.ndarray:
    """Indices of the classes present in the ground truth (non-empty rows)."""
    return np.flatnonzero(conf.sum(axis=1) > 0)


def iou_per_class(conf: np.ndarray) -> np.ndarray:
    """(C,) IoU of each class; NaN where the class appears in neither ground truth nor prediction."""
    tp = np.diag(conf).astype(np.float64)
    denom = conf.sum(axis=0) + conf.sum(axis=1) - np.diag(conf)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(denom > 0, tp / denom, np.nan)


def mean_iou(conf: np.ndarray) -> float:
    """Mean IoU over the classes present in the ground truth (NaN if there is no ground truth).

    Example:
        >>> mean_iou(np.array([[3, 1], [0, 2]]))  # IoU 3/4 and 2/3
        0.7083333333333333
    """
    classes = present_classes(conf)
    return float(np.mean(iou_per_class(conf)[classes])) if len(classes) else math.nan


def pixel_accuracy(conf: np.ndarray) -> float:
    """Correct pixels over all pixels (NaN if there are none)."""
    total = conf.sum()
    return float(np.trace(conf) / total) if total else math.nan


def mean_pixel_accuracy(conf: np.ndarray) -> float:
    """Mean over the present classes of the share of their pixels predicted correctly (recall)."""
    classes = present_classes(conf)
    if not len(classes):
        return math.nan
    recall = np.diag(conf)[classes] / conf.sum(axis=1)[classes]
    return float(np.mean(recall))


def segmentation_metrics(conf: np.ndarray) -> dict[str, float]:
    """mIoU, PA, MPA and their object-only variants of one confusion matrix (conventions §5 key names)."""
    obj = object_only(conf)
    return {
        "mIoU": mean_iou(conf),
        "PA": pixel_accuracy(conf),
        "MPA": mean_pixel_accuracy(conf),
        "mIoU_object": mean_iou(obj),
        "PA_object": pixel_accuracy(obj),
        "MPA_object": mean_pixel_accuracy(obj),
    }
