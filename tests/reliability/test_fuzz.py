"""Property-based tests: the dataset reader, the pose checks and the metric functions never misbehave."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from affnerf.data.format import check_pose, parse_index, parse_transforms
from affnerf.errors import AffnerfError
from affnerf.metrics.segmentation import (
    confusion_matrix,
    mean_iou,
    mean_pixel_accuracy,
    pixel_accuracy,
    segmentation_metrics,
)

JSONISH = st.recursive(
    st.none() | st.booleans() | st.integers(-5, 300) | st.floats(allow_nan=True) | st.text(max_size=6),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=12), inner, max_size=5),
    max_leaves=20,
)
KEYS = [
    "object_id",
    "category",
    "w",
    "h",
    "fl_x",
    "fl_y",
    "cx",
    "cy",
    "frames",
    "parts",
    "affordance_classes",
    "background_color",
    "depth_unit_scale_factor",
    "format",
    "objects",
]


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(st.dictionaries(st.sampled_from(KEYS), JSONISH, max_size=12) | JSONISH)
def test_readers_accept_or_refuse_with_a_clear_error(data):
    for parse in (parse_transforms, parse_index):
        try:
            parse(data, Path("x.json"))
        except AffnerfError as exc:
            assert str(exc).startswith("x.json: ") and "\n" not in str(exc)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=32), min_size=16, max_size=16))
def test_pose_check_refuses_anything_but_rigid_transforms(values):
    matrix = np.array(values, dtype=np.float64).reshape(4, 4)
    try:
        pose = check_pose(matrix.tolist(), Path("t.json"))
    except AffnerfError as exc:
        assert str(exc).startswith("t.json: ")
        return
    assert np.isfinite(pose).all()
    np.testing.assert_allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=2e-3)


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(-10, 10), st.floats(-10, 10), st.floats(-10, 10))
def test_pose_check_accepts_every_rigid_transform(seed, x, y, z):
    pose = np.eye(4)
    pose[:3, :3] = Rotation.random(random_state=seed).as_matrix()
    pose[:3, 3] = [x, y, z]
    np.testing.assert_array_equal(check_pose(pose.tolist(), Path("t.json")), pose)


@settings(max_examples=200, deadline=None)
@given(st.integers(2, 6), st.data())
def test_metrics_are_bounded_and_label_permutation_invariant(num_classes, data):
    n = data.draw(st.integers(1, 60))
    gt = np.array(data.draw(st.lists(st.integers(0, num_classes - 1), min_size=n, max_size=n)))
    pred = np.array(data.draw(st.lists(st.integers(0, num_classes - 1), min_size=n, max_size=n)))
    conf = confusion_matrix(gt, pred, num_classes)
    assert conf.sum() == n
    for value in segmentation_metrics(conf).values():
        assert math.isnan(value) or 0.0 <= value <= 1.0
    assert mean_iou(conf) <= mean_pixel_accuracy(conf) + 1e-12  # IoU never exceeds recall, class by class
    perm = np.random.default_rng(n).permutation(num_classes)
    permuted = confusion_matrix(perm[gt], perm[pred], num_classes)
    assert math.isclose(mean_iou(permuted), mean_iou(conf), rel_tol=1e-12)
    assert math.isclose(pixel_accuracy(permuted), pixel_accuracy(conf), rel_tol=1e-12)
    assert mean_iou(confusion_matrix(gt, gt, num_classes)) == 1.0
