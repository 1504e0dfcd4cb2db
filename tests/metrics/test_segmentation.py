"""Metrics on hand-built confusion matrices."""

from __future__ import annotations

import math

import numpy as np
import pytest

from affnerf.metrics.image import psnr
from affnerf.metrics.segmentation import (
    confusion_matrix,
    iou_per_class,
    mean_iou,
    mean_pixel_accuracy,
    object_only,
    pixel_accuracy,
    segmentation_metrics,
)

# rows: ground truth background, grasp, screw, cut (absent); columns: prediction
CONF = np.array(
    [
        [80, 2, 0, 1],
        [4, 10, 1, 0],
        [2, 3, 5, 0],
        [0, 0, 0, 0],
    ]
)


def test_confusion_matrix_counts_pairs():
    gt = np.array([[0, 0, 1], [2, 1, 1]])
    pred = np.array([[0, 1, 1], [2, 2, 1]])
    assert confusion_matrix(gt, pred, 3).tolist() == [[1, 1, 0], [0, 2, 1], [0, 0, 1]]
    with pytest.raises(ValueError):
        confusion_matrix(gt, pred + 5, 3)


def test_iou_and_miou_over_present_classes():
    iou = iou_per_class(CONF)
    assert iou[0] == pytest.approx(80 / (83 + 86 - 80))
    assert iou[1] == pytest.approx(10 / (15 + 15 - 10))
    assert iou[2] == pytest.approx(5 / (10 + 6 - 5))
    assert iou[3] == 0.0  # predicted once, never in the ground truth: counted in IoU but not averaged
    assert mean_iou(CONF) == pytest.approx((iou[0] + iou[1] + iou[2]) / 3)


def test_pa_and_mpa():
    assert pixel_accuracy(CONF) == pytest.approx(95 / 108)
    assert mean_pixel_accuracy(CONF) == pytest.approx((80 / 83 + 10 / 15 + 5 / 10) / 3)


def test_object_only_variant_drops_background_pixels_and_class():
    obj = object_only(CONF)
    m = segmentation_metrics(CONF)
    assert m["PA_object"] == pytest.approx(15 / 25)  # object pixels predicted right, background misses count
    assert m["MPA_object"] == pytest.approx((10 / 15 + 5 / 10) / 2)
    assert m["mIoU_object"] == pytest.approx((10 / (15 + 13 - 10) + 5 / (10 + 6 - 5)) / 2)
    assert obj[0].sum() == 0


def test_perfect_and_empty():
    perfect = np.diag([5, 3, 0])
    assert segmentation_metrics(perfect) == {
        k: 1.0 for k in ("mIoU", "PA", "MPA", "mIoU_object", "PA_object", "MPA_object")
    }
    assert math.isnan(mean_iou(np.zeros((3, 3), int)))


def test_psnr():
    a = np.zeros((4, 4, 3))
    assert psnr(a, a) == math.inf
    assert psnr(a, a + 0.1) == pytest.approx(20.0)
