"""3D supervision points: inside/outside and nearest-face labels of known shapes, and their cache."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from affnerf.errors import AffnerfError
from affnerf.meshio import LabelledMesh, write_labelled_ply
from affnerf.solid import inside_mesh
from affnerf.train import cache as cache_module
from affnerf.train.cache import cached_points
from affnerf.train.points import (
    DISTANCE_TRUNCATION,
    LABEL_BAND,
    make_point_set,
    part_face_weights,
    split_counts,
)

SIGMAS = (0.005, 0.02)


def _box(top_label: int = 2, side_label: int = 1) -> LabelledMesh:
    """A 0.2 m cube at the origin whose two +z faces are ``top_label`` and the others ``side_label``."""
    box = trimesh.creation.box(extents=(0.2, 0.2, 0.2))
    labels = np.where(box.face_normals[:, 2] > 0.5, top_label, side_label)
    return LabelledMesh(np.asarray(box.vertices), np.asarray(box.faces), face_props={"affordance": labels})


def test_box_points_are_inside_exactly_where_the_box_is_and_take_the_nearest_face():
    total = 20000
    ps = make_point_set(_box(), 0.25, SIGMAS, seed=0, total=total)
    p = np.asarray(ps.points, np.float64)
    assert p.shape == (total, 3) and ps.points.dtype == np.float32 and np.abs(p).max() <= 0.25
    depth = 0.1 - np.abs(p).max(axis=1)  # > 0 inside, distance to the nearest face for inside points
    clear = np.abs(depth) > 1e-4
    np.testing.assert_array_equal(ps.occupancy[clear], (depth > 0)[clear])
    uniform = split_counts(total, 2)[0]
    assert abs(ps.occupancy[:uniform].mean() - 0.4**3) < 0.015  # (0.2 / 0.5)^3 of the cube
    assert 0.3 < ps.occupancy[uniform:].mean() < 0.55  # near-surface points: about half inside
    top_inside = (depth > 0) & (p[:, 2] > 0.09) & (np.abs(p[:, :2]).max(axis=1) < 0.05)
    top_outside = (p[:, 2] > 0.1 + 1e-3) & (p[:, 2] < 0.1 + LABEL_BAND - 1e-3) & (np.abs(p[:, :2]).max(axis=1) < 0.09)
    bottom = (depth > 0) & (p[:, 2] < -0.05)
    far = np.abs(p).max(axis=1) > 0.1 + LABEL_BAND + 1e-3
    assert min(top_inside.sum(), top_outside.sum(), bottom.sum(), far.sum()) > 50
    assert (ps.labels[top_inside] == 2).all() and (ps.labels[top_outside] == 2).all()
    assert (ps.labels[bottom] == 1).all() and (ps.labels[far] == 0).all()
    assert (ps.labels[ps.occupancy == 1] > 0).all()  # every inside point has a target


def test_box_signed_distances_match_the_box_within_the_sample_spacing_and_stop_at_the_truncation():
    ps = make_point_set(_box(), 0.25, SIGMAS, seed=2, total=12000)
    p = np.asarray(ps.points, np.float64)
    outside = np.linalg.norm(np.maximum(np.abs(p) - 0.1, 0.0), axis=1)
    true = np.where(outside > 0, outside, np.abs(p).max(axis=1) - 0.1)  # the box's signed distance
    got = np.asarray(ps.distance, np.float64)
    assert ps.distance.dtype == np.float16 and np.abs(got).max() <= DISTANCE_TRUNCATION + 1e-4
    clipped = np.clip(true, -DISTANCE_TRUNCATION, DISTANCE_TRUNCATION)
    assert np.abs(got - clipped).max() < 0.003  # surface samples about 1 mm apart on a 0.2 m box
    np.testing.assert_array_equal(got < 0, ps.occupancy == 1)
    assert (np.abs(true) > DISTANCE_TRUNCATION).sum() > 500  # far points are there and hold +-the truncation


def test_sphere_inside_fraction_and_surface_band():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.15)
    mesh = LabelledMesh(sphere.vertices, sphere.faces, face_props={"affordance": np.full(len(sphere.faces), 7)})
    ps = make_point_set(mesh, 0.25, SIGMAS, seed=1, total=16000)
    r = np.linalg.norm(ps.points, axis=1)
    clear = np.abs(r - 0.15) > 1e-3
    np.testing.assert_array_equal(ps.occupancy[clear], (r < 0.15)[clear])
    assert abs(ps.occupancy[:4000].mean() - 4 / 3 * np.pi * 0.15**3 / 0.5**3) < 0.015
    assert set(np.unique(ps.labels[(r < 0.15 + LABEL_BAND - 1e-3)])) == {7}
    assert (ps.labels[r > 0.15 + LABEL_BAND + 1e-3] == 0).all()


def test_interpenetrating_closed_parts_are_inside_where_they_overlap():
    a = trimesh.creation.box(extents=(0.2, 0.1, 0.1))
    b = trimesh.creation.box(extents=(0.1, 0.1, 0.2))
    both = trimesh.util.concatenate([a, b])  # two closed boxes crossing at the origin, not merged
    points = np.array([[0.0, 0.0, 0.0], [0.02, 0.01, -0.03], [0.08, 0.0, 0.0], [0.0, 0.0, 0.08], [0.08, 0.0, 0.08]])
    assert inside_mesh(both, points).tolist() == [True, True, True, True, False]


def test_a_sphere_with_holes_is_still_mostly_right():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.15)
    keep = np.random.default_rng(0).random(len(sphere.faces)) > 0.03  # 3 % of the faces missing
    holed = trimesh.Trimesh(sphere.vertices, sphere.faces[keep], process=False)
    assert not holed.is_watertight
    rng = np.random.default_rng(1)
    inner = rng.normal(size=(3000, 3))
    inner *= (rng.uniform(0.0, 0.13, 3000) / np.linalg.norm(inner, axis=1))[:, None]
    outer = rng.uniform(-0.25, 0.25, (6000, 3))
    outer = outer[np.linalg.norm(outer, axis=1) > 0.17]
    assert inside_mesh(holed, inner).mean() > 0.99
    assert inside_mesh(holed, outer).mean() < 0.01


def test_point_cache_is_reused_and_rebuilt_when_its_source_or_settings_change(tmp_path, monkeypatch):
    made = []
    real = cache_module.make_point_set
    monkeypatch.setattr(cache_module, "make_point_set", lambda *a, **k: made.append(1) or real(*a, **k))
    mesh = tmp_path / "mesh.ply"
    write_labelled_ply(mesh, _box(top_label=2))
    first = cached_points(mesh, "box", tmp_path / "cache", 0.25, SIGMAS, total=4096)
    again = cached_points(mesh, "box", tmp_path / "cache", 0.25, SIGMAS, total=4096)
    assert len(made) == 1 and sorted(p.name for p in (tmp_path / "cache").iterdir()) == ["box.points"]
    np.testing.assert_array_equal(first.labels, again.labels)
    elsewhere = cached_points(mesh, "box", tmp_path / "other", 0.25, SIGMAS, total=4096)
    np.testing.assert_array_equal(first.points, elsewhere.points)  # seeded by the object id alone
    write_labelled_ply(mesh, _box(top_label=4))  # the object is regenerated with other labels
    relabelled = cached_points(mesh, "box", tmp_path / "cache", 0.25, SIGMAS, total=4096)
    assert len(made) == 3 and 4 in set(relabelled.labels.tolist()) and 2 not in set(relabelled.labels.tolist())
    cached_points(mesh, "box", tmp_path / "cache", 0.25, (0.005, 0.03), total=4096)
    assert len(made) == 4
    (tmp_path / "cache" / "box.points" / "meta.json").unlink()  # as if a copy was cut short
    cached_points(mesh, "box", tmp_path / "cache", 0.25, (0.005, 0.03), total=4096)
    assert len(made) == 5 and sorted(p.name for p in (tmp_path / "cache").iterdir()) == ["box.points"]
    cached_points(mesh, "box", tmp_path / "cache", 0.25, (0.005, 0.03), total=4096, part_balance=1.0)
    assert len(made) == 6  # another part balance is another point set
    half = cached_points(mesh, "box", tmp_path / "cache", 0.25, (0.005, 0.03), total=4096, uniform_share=0.5)
    assert len(made) == 7  # and so is another uniform share

    def far(points):  # share beyond 0.2 m on some axis: the box's half side is 0.1, so only uniform draws
        return float((np.abs(points).max(axis=1) > 0.2).mean())

    assert far(half.points) > 1.5 * far(relabelled.points)  # 0.5 uniform against the default quarter


def test_a_missing_mesh_or_one_without_affordance_is_a_clear_error(tmp_path):
    with pytest.raises(AffnerfError, match="mesh.ply: file not found"):
        cached_points(tmp_path / "mesh.ply", "x", tmp_path / "cache", 0.25, SIGMAS)
    box = _box()
    write_labelled_ply(tmp_path / "mesh.ply", LabelledMesh(box.vertices, box.faces))
    with pytest.raises(AffnerfError, match="no per-face 'affordance'"):
        cached_points(tmp_path / "mesh.ply", "x", tmp_path / "cache", 0.25, SIGMAS)
    assert not any((tmp_path / "cache").iterdir())  # nothing half-written left behind


def test_part_balance_gives_every_part_the_same_share_of_the_surface_samples():
    labels = np.array([1, 1, 1, 2])
    areas = np.array([4.0, 3.0, 1.0, 0.5])
    for balance, share_of_small in ((0.0, 0.5 / 8.5), (1.0, 0.5), (0.5, 0.5**0.5 / (0.5**0.5 + 8**0.5))):
        w = part_face_weights(areas, labels, balance)
        assert w[labels == 2].sum() / w.sum() == pytest.approx(share_of_small)
        assert w[0] / w[1] == pytest.approx(4.0 / 3.0)  # inside a part, still by area


def test_a_small_part_gets_more_near_surface_points_with_part_balance():
    """The cube's +z side is 1/6 of its surface (2 of 12 faces): area-weighted it gets about a sixth of the
    near-surface points, balanced about half (the uniform quarter adds about 0.08 to both); the inside test holds."""

    def top_share(points) -> float:
        near_top = points.points[:, 2] > 0.09
        return float(near_top.mean())

    plain = make_point_set(_box(), 0.25, SIGMAS, seed=3, total=8192)
    balanced = make_point_set(_box(), 0.25, SIGMAS, seed=3, total=8192, part_balance=1.0)
    assert top_share(plain) < 0.3 < 0.4 < top_share(balanced)
    inside = np.all(np.abs(balanced.points) < 0.1, axis=1)
    np.testing.assert_array_equal(balanced.occupancy.astype(bool), inside)


def _capped_rod() -> LabelledMesh:
    """A pen-like rod along x (radius 10 mm, label 1) whose +x half is covered by a cap (radius 12 mm, label 5)."""
    rod = trimesh.creation.cylinder(radius=0.01, height=0.2, sections=48, transform=_along_x(0.0))
    cap = trimesh.creation.cylinder(radius=0.012, height=0.1, sections=48, transform=_along_x(0.055))
    both = trimesh.util.concatenate([rod, cap])
    labels = np.r_[np.full(len(rod.faces), 1), np.full(len(cap.faces), 5)]
    return LabelledMesh(np.asarray(both.vertices), np.asarray(both.faces), face_props={"affordance": labels})


def _along_x(offset: float) -> np.ndarray:
    turn = trimesh.transformations.rotation_matrix(np.pi / 2, (0.0, 1.0, 0.0))
    turn[0, 3] = offset
    return turn


def test_a_face_hidden_under_another_part_gives_no_label_or_distance():
    # Just under the cap's skin (radius 10.5-11.5 mm) the nearest face is the rod's hidden one (0.5-1.5 mm away)
    # but the surface a camera sees is the cap's: the label must be the cap's and the distance to the cap.
    mesh = _capped_rod()
    ps = make_point_set(mesh, 0.25, (0.002,), seed=0, total=40000)
    p = np.asarray(ps.points, np.float64)
    radius = np.hypot(p[:, 1], p[:, 2])
    under_cap = (p[:, 0] > 0.02) & (p[:, 0] < 0.09) & (radius > 0.0105) & (radius < 0.0115)
    assert under_cap.sum() > 50 and (ps.occupancy[under_cap] == 1).all()
    assert (ps.labels[under_cap] == 5).all()
    got = np.asarray(ps.distance[under_cap], np.float64)
    np.testing.assert_allclose(got, radius[under_cap] - 0.012, atol=1.5e-3)
    bare = (p[:, 0] < -0.02) & (p[:, 0] > -0.08) & (radius > 0.0085) & (radius < 0.0095)
    assert bare.sum() > 50 and (ps.labels[bare] == 1).all()  # the visible rod keeps its label
