"""3D metrics on hand-built meshes: spheres, offset squares, swapped labels, an empty prediction."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from affnerf.metrics.surface import (
    FSCORE_TAU,
    SURFACE_KEYS,
    chamfer_l1,
    fscore,
    label_miou,
    sample_surface,
    surface_metrics,
)


def _sphere(radius: float = 1.0, centre=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An icosphere with faces above z = centre labelled 1 and below labelled 2."""
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=radius)
    vertices = np.asarray(mesh.vertices) + np.asarray(centre)
    faces = np.asarray(mesh.faces)
    labels = np.where(vertices[faces].mean(axis=1)[:, 2] > centre[2], 1, 2)
    return vertices, faces, labels


def _square(side: float, z: float, label: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    vertices = np.array([[0, 0, z], [side, 0, z], [side, side, z], [0, side, z]], np.float64)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]]), np.array([label, label])


def test_sampling_is_area_weighted_seeded_and_labelled():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [3, 0, 1], [0, 2, 1]], np.float64)
    faces = np.array([[0, 1, 2], [3, 4, 5]])  # areas 0.5 and 3
    a = sample_surface(vertices, faces, np.array([4, 7]), count=20_000, rng=1)
    b = sample_surface(vertices, faces, np.array([4, 7]), count=20_000, rng=1)
    np.testing.assert_array_equal(a.points, b.points)
    assert len(a) == 20_000 and a.points.shape == (20_000, 3)
    assert (a.labels == 4).mean() == pytest.approx(0.5 / 3.5, abs=0.01)
    upper = a.points[a.labels == 7]
    assert np.allclose(upper[:, 2], 1.0) and (upper[:, 0] / 3 + upper[:, 1] / 2 <= 1 + 1e-9).all()
    assert not np.array_equal(a.points, sample_surface(vertices, faces, np.array([4, 7]), 20_000, rng=2).points)


def test_identical_meshes_score_perfectly():
    sphere = _sphere(0.1)
    same = sample_surface(*sphere, rng=0)
    m = surface_metrics(same, same)
    assert m == {"chamfer_l1": 0.0, "fscore_1cm": 1.0, "affordance_miou_3d": 1.0}
    other = surface_metrics(sample_surface(*sphere, rng=5), same)  # other samples of the same surface
    assert other["chamfer_l1"] < 0.002 and other["fscore_1cm"] == 1.0 and other["affordance_miou_3d"] > 0.98


def test_a_scaled_sphere_is_off_by_the_radius_difference():
    true = sample_surface(*_sphere(0.1), rng=0)
    bigger = sample_surface(*_sphere(0.12), rng=1)  # every point 2 cm out: beyond tau
    m = surface_metrics(bigger, true)
    assert m["chamfer_l1"] == pytest.approx(0.02, rel=0.05)
    assert m["fscore_1cm"] == 0.0
    assert m["affordance_miou_3d"] > 0.97  # same halves, labels transfer radially
    assert m["chamfer_l1"] == pytest.approx(chamfer_l1(bigger.points, true.points))
    near = sample_surface(*_sphere(0.105), rng=1)  # 5 mm out: within tau, but not every sample pairs up
    assert surface_metrics(near, true)["fscore_1cm"] == pytest.approx(fscore(near.points, true.points))
    assert 0.5 < fscore(near.points, true.points) <= 1.0


def test_offset_squares_within_and_beyond_tau():
    true = sample_surface(*_square(0.1, 0.0), rng=0)
    near = sample_surface(*_square(0.1, 0.005), rng=1)
    far = sample_surface(*_square(0.1, 0.03), rng=1)
    assert chamfer_l1(far.points, true.points) == pytest.approx(0.03, rel=0.02)
    assert fscore(far.points, true.points) == 0.0
    assert chamfer_l1(near.points, true.points) == pytest.approx(0.005, rel=0.1)
    assert fscore(near.points, true.points) == 1.0
    assert 0.005 < FSCORE_TAU < 0.03


def test_swapped_labels_score_zero_and_one_label_everywhere_scores_half_of_one_class():
    vertices, faces, labels = _sphere(0.1)
    true = sample_surface(vertices, faces, labels, rng=0)
    swapped = sample_surface(vertices, faces, 3 - labels, rng=0)
    assert surface_metrics(swapped, true)["affordance_miou_3d"] == 0.0
    one = sample_surface(vertices, faces, np.ones_like(labels), rng=0)
    assert surface_metrics(one, true)["affordance_miou_3d"] == pytest.approx(0.25, abs=0.01)  # IoU 1/2 and 0


def test_background_is_not_a_class_of_the_3d_miou():
    assert label_miou(np.array([0, 0, 1, 1]), np.array([1, 1, 1, 1])) == 0.5
    assert label_miou(np.array([0, 0]), np.array([0, 0])) is None


def test_an_empty_prediction_scores_zero_and_no_chamfer():
    true = sample_surface(*_sphere(0.1), rng=0)
    empty = sample_surface(np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros(0, np.int64))
    degenerate = sample_surface(np.zeros((3, 3)), np.array([[0, 1, 2]]), np.array([1]))  # no area
    for pred in (empty, degenerate):
        assert len(pred) == 0
        m = surface_metrics(pred, true)
        assert m == {"chamfer_l1": None, "fscore_1cm": 0.0, "affordance_miou_3d": 0.0}
        assert set(m) == set(SURFACE_KEYS)
        assert json.loads(json.dumps(m, allow_nan=False)) == m  # strict JSON
