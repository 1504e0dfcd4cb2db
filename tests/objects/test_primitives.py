"""Mesh builders give closed, outward-oriented surfaces of the right size."""

from __future__ import annotations

import numpy as np
import pytest

from affnerf.objects import primitives as P


def _closed(mesh):
    return mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0


def test_revolved_cylinder_has_the_analytic_volume():
    mesh = P.cylinder(0.05, 0.2, sections=256)
    assert _closed(mesh)
    np.testing.assert_allclose(mesh.volume, np.pi * 0.05**2 * 0.2, rtol=1e-3)
    np.testing.assert_allclose(mesh.bounds, [[-0.05, -0.05, 0.0], [0.05, 0.05, 0.2]], atol=1e-9)


def test_cup_profile_is_hollow():
    cup = P.revolve(np.array([[0, 0], [0.05, 0], [0.06, 0.1], [0.055, 0.1], [0.045, 0.005], [0, 0.005]]))
    assert _closed(cup)
    inside = cup.contains(np.array([[0.0, 0.0, 0.05], [0.05, 0.0, 0.05], [0.0, 0.0, 0.002]]))
    assert inside.tolist() == [False, True, True]  # the cavity is outside the solid; wall and floor inside


def test_ring_torus_volume():
    r, a = 0.1, 0.01
    ring = P.revolve(P.circle(a, 64) + np.array([r, 0.0]), segments=256, closed=True)
    assert _closed(ring)
    np.testing.assert_allclose(ring.volume, 2 * np.pi**2 * r * a**2, rtol=2e-3)


def test_closed_revolve_profile_must_stay_off_axis():
    with pytest.raises(ValueError):
        P.revolve(np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.1]]), closed=True)


def test_tube_along_a_curve_and_a_closed_loop():
    path = P.smooth_curve(np.array([[0, 0, 0], [0.05, 0.02, 0.05], [0.1, 0, 0.1]]), 30)
    tube = P.tube(path, 0.005, sides=32)
    assert _closed(tube)
    length = np.linalg.norm(np.diff(path, axis=0), axis=1).sum()
    np.testing.assert_allclose(tube.volume, np.pi * 0.005**2 * length, rtol=0.03)
    loop = P.tube(P.circle(0.1, 64) @ np.array([[1, 0, 0], [0, 1, 0]]), 0.01, closed=True)
    assert _closed(loop)


def test_sweep_with_tapering_section_and_mirror_stays_oriented():
    path = np.stack([np.zeros(10), np.zeros(10), np.linspace(0, 0.1, 10)], 1)
    wedge = P.sweep(
        path, P.superellipse(1, 1, 8), scales=np.stack([np.full(10, 0.01), np.linspace(0.01, 0.002, 10)], 1)
    )
    assert _closed(wedge)
    mirrored = P.placed(wedge, np.diag([-1.0, 1.0, 1.0, 1.0]))
    assert _closed(mirrored)


def test_extrude_with_hole():
    ring = P.extrude(P.ellipse(0.03, 0.02), 0.004, holes=[P.ellipse(0.025, 0.015)])
    assert _closed(ring)
    np.testing.assert_allclose(ring.volume, np.pi * (0.03 * 0.02 - 0.025 * 0.015) * 0.004, rtol=0.01)


def test_smooth_curve_passes_through_its_ends():
    control = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 1.0]])
    curve = P.smooth_curve(control, 50)
    np.testing.assert_allclose(curve[[0, -1]], control[[0, -1]])
