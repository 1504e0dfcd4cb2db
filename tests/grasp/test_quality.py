"""Ferrari-Canny epsilon and the hold quality: pure functions checked against hand-built cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from scipy.optimize import minimize

from affnerf.grasp.gripper import grasp_pose
from affnerf.grasp.quality import (
    MU,
    TORSION,
    contact_wrenches,
    ferrari_canny,
    friction_cone,
    grasp_wrenches,
    hold_quality,
    hull_margin,
    resisted_scale,
    turned_up_directions,
    wrench_space,
)
from affnerf.grasp.scoring import score_grasps
from affnerf.grasp.target import GraspObject


def _box(extents=(0.04, 0.04, 0.12)) -> GraspObject:
    mesh = trimesh.creation.box(extents=extents)
    return GraspObject(mesh.vertices, mesh.faces, np.ones(len(mesh.faces), np.int64), "box")


def _side_grasp(height: float) -> np.ndarray:
    """Closing along x across the box's 4 cm side, approaching along y, at a height on the box."""
    return grasp_pose(np.array([0.0, 0.0, height]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))[None]


def test_centred_antipodal_box_grasp_is_force_closure_and_off_centre_is_worse():
    box = _box()
    centre = score_grasps(box, _side_grasp(0.0))[0]
    off = score_grasps(box, _side_grasp(0.045))[0]
    assert centre.valid and off.valid
    assert centre.epsilon > 0
    assert 0 < off.epsilon < centre.epsilon
    assert centre.width == pytest.approx(0.04, abs=1e-6)


def test_normals_outside_the_friction_cone_give_zero():
    points = np.array([[-0.02, 0.0, 0.0], [0.02, 0.0, 0.0]])
    tilt = math.radians(40)  # more than atan(0.5) = 26.6 degrees
    inward = np.array([[math.cos(tilt), 0.0, math.sin(tilt)], [-math.cos(tilt), 0.0, math.sin(tilt)]])
    assert ferrari_canny(points, inward, np.zeros(3), 0.07) == 0.0
    inside = math.radians(15)
    inward = np.array([[math.cos(inside), 0.0, math.sin(inside)], [-math.cos(inside), 0.0, math.sin(inside)]])
    assert ferrari_canny(points, inward, np.zeros(3), 0.07) > 0.0


def test_point_contacts_cannot_resist_torque_about_the_grasp_axis():
    points = np.array([[-0.02, 0.0, 0.0], [0.02, 0.0, 0.0]])
    inward = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    assert ferrari_canny(points, inward, np.zeros(3), 0.07, torsion=0.0) == 0.0
    assert ferrari_canny(points, inward, np.zeros(3), 0.07) > 0.0


def test_epsilon_is_invariant_to_moving_mesh_and_grasp_together():
    box = _box()
    pose = _side_grasp(0.02)
    base = score_grasps(box, pose)[0].epsilon
    moved = trimesh.transformations.random_rotation_matrix(np.random.default_rng(3).random(3))
    moved[:3, 3] = [0.3, -0.2, 0.5]
    vertices = box.vertices @ moved[:3, :3].T + moved[:3, 3]
    other = GraspObject(vertices, box.faces, box.face_affordance, "moved")
    assert score_grasps(other, moved @ pose)[0].epsilon == pytest.approx(base, rel=1e-5)


def test_hull_margin_of_the_cross_polytope_is_one_over_root_six():
    assert hull_margin(np.vstack([np.eye(6), -np.eye(6)])) == pytest.approx(1 / math.sqrt(6))
    assert hull_margin(np.vstack([np.eye(6), -np.eye(6)])[:-1]) == 0.0  # origin on the boundary
    assert hull_margin(np.eye(6)[:3]) == 0.0  # flat


def test_two_contact_case_by_hand():
    """Two soft fingers squeezing a sphere of radius r = 0.05 through its centre along x (mu 0.5, 4 cone edges)."""
    r, mu, gamma = 0.05, 0.5, 0.0025
    points = np.array([[-r, 0.0, 0.0], [r, 0.0, 0.0]])
    inward = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    w = contact_wrenches(points[0], inward[0], np.zeros(3), r, mu=mu, edges=4, torsion=gamma)
    # every force has unit normal component and tangential part mu; torque = (p x f) / r = (0, fz, -fy)
    np.testing.assert_allclose(w[:4, 0], 1.0)
    np.testing.assert_allclose(np.linalg.norm(w[:4, 1:3], axis=1), mu)
    np.testing.assert_allclose(w[:4, 3:], np.stack([np.zeros(4), w[:4, 2], -w[:4, 1]], 1), atol=1e-12)
    # the soft-finger wrenches: normal force and a torsional moment +-gamma about the normal, over r
    np.testing.assert_allclose(w[4:], [[1, 0, 0, gamma / r, 0, 0], [1, 0, 0, -gamma / r, 0, 0]], atol=1e-12)
    eps = ferrari_canny(points, inward, np.zeros(3), r, mu=mu, edges=4, torsion=gamma)
    # independent check: epsilon is the smallest support value h(u) = max_k w_k . u over unit directions u,
    # found here by local minimisation from many starts
    all_w = np.concatenate([w, contact_wrenches(points[1], inward[1], np.zeros(3), r, mu=mu, edges=4, torsion=gamma)])

    def support(u):
        return (all_w @ (u / np.linalg.norm(u))).max()

    starts = np.random.default_rng(0).normal(size=(24, 6))
    found = min(
        minimize(support, s0, method="Nelder-Mead", options={"xatol": 1e-8, "fatol": 1e-10, "maxiter": 4000}).fun
        for s0 in starts
    )
    assert eps == pytest.approx(found, rel=0.01)
    # the weakest direction is twisting about the grasp axis: the torsion bound gamma / r over a unit of force
    assert eps <= gamma / r


def test_cone_edges_are_evenly_spread():
    f = friction_cone(np.array([0.0, 1.0, 0.0]), mu=0.3, edges=8)
    tangential = f - f[:, 1:2] * np.array([0.0, 1.0, 0.0])
    angles = np.sort(np.arctan2(tangential[:, 2], tangential[:, 0]))
    np.testing.assert_allclose(np.diff(angles), 2 * np.pi / 8, atol=1e-12)


def _pinch(centre: np.ndarray, axis: np.ndarray, approach: np.ndarray) -> np.ndarray:
    """Primitive wrenches of two soft-finger contacts 2 cm apart along ``axis`` about ``centre``, centroid at 0."""
    points = np.stack([centre - 0.01 * axis, centre + 0.01 * axis])
    return grasp_wrenches(points, np.stack([axis, -axis]), np.zeros(3), 0.1, reference=approach)


def test_resisted_scale_reaches_the_facet_a_direction_leaves_through():
    cube = wrench_space(np.array(np.meshgrid(*[[-1.0, 1.0]] * 6)).reshape(6, -1).T)
    assert resisted_scale(cube, np.array([0.0, 0.0, 0.5, 0, 0, 0])) == pytest.approx(2.0)
    assert resisted_scale(cube, np.array([0.25, 0.0, 0.5, 0, 0, 0])) == pytest.approx(2.0)  # z still leaves first
    # the origin on the boundary: nothing along a direction that leaves at once, up to the facet otherwise
    half = wrench_space(np.vstack([np.eye(6), -np.eye(6)[1:]]))
    assert resisted_scale(half, -np.eye(6)[0]) == 0.0
    assert resisted_scale(half, np.eye(6)[0]) == pytest.approx(1.0)


def test_a_centred_pinch_carries_mu_of_the_normal_force_in_any_turn():
    x, z = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    wrenches = _pinch(np.zeros(3), x, np.array([0.0, 1.0, 0.0]))
    # two fingers share a unit normal force; friction carries mu of it whichever way the weight pulls in the pads
    assert hold_quality(wrenches, z, x) == pytest.approx(MU, rel=0.1)
    assert hold_quality(wrenches, z, x) <= MU + 1e-9


def test_a_pinch_far_from_the_centre_of_mass_carries_little_as_a_teapot_handle():
    x, z = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    centred = hold_quality(_pinch(np.zeros(3), x, np.array([0.0, 1.0, 0.0])), z, x)
    handle = hold_quality(_pinch(np.array([0.0, 0.08, 0.0]), x, np.array([0.0, 1.0, 0.0])), z, x)
    # the weight's moment about the contacts (8 cm arm) is held only by the pads' torsion (TORSION per unit force)
    assert handle == pytest.approx(TORSION / 0.08, rel=0.2)
    assert handle < 0.1 * centred


def test_turning_about_the_closing_axis_costs_a_grasp_that_holds_only_upright():
    x, z = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    # closing vertically above the centre of mass: upright the weight presses along the closing axis into a finger
    wrenches = _pinch(np.array([0.0, 0.0, 0.05]), z, x)
    upright = hold_quality(wrenches, z, z, turns=(0.0,))
    assert upright > 0.4
    # a horizontal closing axis 5 cm above the centre: upright fine, turned by 90 degrees the weight hangs off it
    side = _pinch(np.array([0.0, 0.0, 0.05]), x, z)
    assert hold_quality(side, z, x, turns=(0.0,)) > 10 * hold_quality(side, z, x)


def test_turned_up_directions_rotate_about_the_axis_and_carry_no_torque():
    dirs = turned_up_directions(np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), (0.0, 90.0, -90.0))
    assert np.allclose(dirs[:, 3:], 0.0)
    assert np.allclose(dirs[0, :3], [0, 0, 1]) and np.allclose(np.abs(dirs[1:, 1]), 1.0)
    assert np.allclose(np.linalg.norm(dirs[:, :3], axis=1), 1.0)
