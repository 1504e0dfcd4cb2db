"""The pybullet lift test: grasps that hold lift the object, bad grasps fail for the right reason, the collision
shape is a convex decomposition, and masses and frictions are what the configuration says."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pybullet
import pytest
import trimesh
from pybullet_utils.bullet_client import BulletClient
from shapely.geometry import Polygon

from affnerf.errors import AffnerfError
from affnerf.grasp.convex import convex_parts
from affnerf.grasp.gripper import ParallelJawGripper, grasp_pose
from affnerf.grasp.physics import FINGER_LINKS, LiftConfig, add_gripper, add_object, lift_test

X, Y, Z = np.eye(3)
BOX = trimesh.creation.box(extents=[0.04, 0.04, 0.12])  # centred on the origin, long along z
ROD = trimesh.creation.box(extents=[0.25, 0.02, 0.02])  # long along x
L_SHAPE = trimesh.creation.extrude_polygon(
    Polygon([(0, 0), (0.1, 0), (0.1, 0.03), (0.03, 0.03), (0.03, 0.1), (0, 0.1)]), 0.03
)


@pytest.fixture
def client():
    """A fresh headless pybullet client, disconnected afterwards."""
    c = BulletClient(connection_mode=pybullet.DIRECT)
    yield c
    c.disconnect()


@pytest.mark.parametrize(
    "centre, approach",
    [((0.0, 0.0, 0.0), Y), ((0.0, 0.0, 0.05), -Z)],
    ids=["middle-from-side", "top-from-above"],
)
def test_centred_grasp_across_a_box_lifts_it(centre, approach):
    result = lift_test(BOX, grasp_pose(np.array(centre), X, approach), 0.04)
    assert result.success and result.held and result.reason == "ok"
    assert result.lifted == pytest.approx(0.10, abs=0.005)


def test_lift_test_is_deterministic():
    pose = grasp_pose(np.zeros(3), X, Y)
    assert lift_test(BOX, pose, 0.04) == lift_test(BOX, pose, 0.04)


def test_a_lift_test_prints_nothing_and_leaves_standard_output_working(capfd):
    print("before", flush=True)
    assert lift_test(BOX, grasp_pose(np.zeros(3), X, Y), 0.04).success
    print("after", flush=True)
    out, _ = capfd.readouterr()
    assert out == "before\nafter\n"  # pybullet's "argv[0]=" of each connection is not in a long run's log


def test_closing_on_empty_space_beside_the_box_fails():
    result = lift_test(BOX, grasp_pose(np.array([0.1, 0.0, 0.0]), X, Y), 0.04)
    assert not result.success and not result.held
    assert result.reason == "no contact"
    assert result.lifted == 0.0


def test_gripper_starting_inside_the_object_is_reported():
    # Fingers 1.4 cm apart straddle the box's centre line 5 cm above its centre: inside the 12 cm tall box.
    result = lift_test(BOX, grasp_pose(np.zeros(3), X, -Z), 0.0)
    assert (result.success, result.reason) == (False, "collision at start")


def test_palm_hitting_the_object_on_the_way_in_is_reported():
    # Grasping the middle of the 12 cm box from above: the 5 cm fingers are too short, the palm hits the top.
    result = lift_test(BOX, grasp_pose(np.zeros(3), X, -Z), 0.04)
    assert (result.success, result.reason) == (False, "collision on approach")


@pytest.mark.parametrize(
    "x, friction, reasons",
    [
        (0.115, 0.8, {"ok"}),  # the rod's very end, normal friction: friction torque at the pads holds it level
        (0.115, 0.05, {"dropped", "slipped"}),  # the very end, very low friction: gripped, then turns and slips
        (0.0, 0.05, {"ok"}),  # the middle with the same low friction: no torque, friction carries the weight
        (0.0, 0.0, {"no contact", "dropped", "slipped"}),  # no friction at all: nothing carries the weight
    ],
)
def test_rod_grasped_at_its_end_needs_friction(x, friction, reasons):
    config = replace(LiftConfig(), object_friction=friction)
    result = lift_test(ROD, grasp_pose(np.array([x, 0.0, 0.0]), Y, -Z), 0.02, config=config)
    assert result.reason in reasons
    assert result.success is (reasons == {"ok"})
    assert (result.lifted > 0.09) is result.success


def test_non_convex_shape_decomposes_into_convex_parts_covering_it():
    parts = convex_parts(L_SHAPE)
    assert len(parts) >= 2
    assert all(part.is_convex and part.volume > 0 for part in parts)
    union = trimesh.util.concatenate(parts)
    np.testing.assert_allclose(union.bounds, L_SHAPE.bounds, atol=1e-3)
    volume = sum(part.volume for part in parts)
    assert volume == pytest.approx(L_SHAPE.volume, rel=0.1)
    assert volume < 0.8 * L_SHAPE.convex_hull.volume  # not the hull


def test_union_of_closed_parts_keeps_each_part():
    cup = trimesh.util.concatenate(
        [  # a base plate and a wall standing on it, overlapping
            trimesh.creation.box(extents=[0.1, 0.1, 0.01]),
            trimesh.creation.box(
                extents=[0.01, 0.1, 0.1], transform=trimesh.transformations.translation_matrix([0.045, 0.0, 0.05])
            ),
        ]
    )
    parts = convex_parts(cup)
    assert len(parts) == 2
    np.testing.assert_allclose(trimesh.util.concatenate(parts).bounds, cup.bounds, atol=1e-9)


def test_convex_parts_are_cached_copies():
    first = convex_parts(L_SHAPE)
    first[0].apply_translation([1.0, 0.0, 0.0])
    again = convex_parts(L_SHAPE)
    np.testing.assert_allclose(trimesh.util.concatenate(again).bounds, L_SHAPE.bounds, atol=1e-3)


def test_flat_mesh_is_rejected():
    flat = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], faces=[[0, 1, 2], [1, 3, 2]])
    with pytest.raises(AffnerfError, match="no volume"):
        convex_parts(flat)


def test_collision_shape_is_the_decomposition_not_the_hull(client):
    obj = add_object(client, convex_parts(L_SHAPE), LiftConfig())
    probe = client.createMultiBody(
        0.01, client.createCollisionShape(pybullet.GEOM_SPHERE, radius=0.005), basePosition=[0.07, 0.07, 0.015]
    )  # in the L's notch, inside its hull
    distances = [p[8] for p in client.getClosestPoints(obj, probe, 0.1)]
    assert distances and min(distances) > 0.02


def test_object_mass_inertia_and_friction_are_set_from_the_config(client):
    config = LiftConfig(
        mass=0.37, object_friction=0.55, spinning_friction=0.003, rolling_friction=0.0002, restitution=0.1
    )
    box = trimesh.creation.box(extents=[0.02, 0.04, 0.1])
    box.apply_translation([0.1, 0.2, 0.3])
    obj = add_object(client, convex_parts(box), config)
    info = client.getDynamicsInfo(obj, -1)
    assert info[0] == pytest.approx(0.37)  # mass
    assert info[1] == pytest.approx(0.55)  # lateral friction
    assert (info[5], info[6], info[7]) == pytest.approx((0.1, 0.0002, 0.003))  # restitution, rolling, spinning
    a, b, c = 0.02, 0.04, 0.1
    expected = sorted(0.37 / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b]))
    np.testing.assert_allclose(sorted(info[2]), expected, rtol=1e-6)
    np.testing.assert_allclose(client.getBasePositionAndOrientation(obj)[0], [0.1, 0.2, 0.3], atol=1e-9)


def test_gripper_links_match_the_gripper_boxes_and_config(client):
    gripper, opening = ParallelJawGripper(), 0.05
    config = LiftConfig(finger_friction=0.9, finger_mass=0.03, palm_mass=0.4, spinning_friction=0.004)
    grip = add_gripper(client, gripper, opening, np.eye(4), config)
    (c1, h1), (c2, h2), (cp, hp) = gripper.boxes(opening)
    for link, (centre, half) in zip(
        (FINGER_LINKS[0], FINGER_LINKS[1], -1), ((c1, h1), (c2, h2), (cp, hp)), strict=True
    ):
        low, high = client.getAABB(grip, link)
        np.testing.assert_allclose(low, centre - half, atol=1e-6)
        np.testing.assert_allclose(high, centre + half, atol=1e-6)
        info = client.getDynamicsInfo(grip, link)
        assert info[0] == pytest.approx(0.4 if link == -1 else 0.03)
        assert (info[1], info[7]) == pytest.approx((0.9, 0.004))


@pytest.mark.parametrize(
    "pose, width, message",
    [
        (np.full((4, 4), np.nan), 0.04, "finite 4x4"),
        (np.diag([1.0, 1.0, -1.0, 1.0]), 0.04, "not a rotation"),
        (np.eye(4), 0.2, "outside"),
    ],
)
def test_malformed_grasps_are_rejected(pose, width, message):
    with pytest.raises(AffnerfError, match=message):
        lift_test(BOX, pose, width)


def test_config_rejects_impossible_values():
    with pytest.raises(AffnerfError, match="mass"):
        LiftConfig(mass=0.0)
    with pytest.raises(AffnerfError, match="object_friction"):
        LiftConfig(object_friction=-0.1)
