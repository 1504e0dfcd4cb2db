"""Lift-and-disturb: a firm grasp stays put through the turn and the shake, a grasp that only just lifts does
not, and a failed lift is never disturbed."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import trimesh

from affnerf.grasp.disturb import DisturbConfig, lift_and_disturb, shake_offsets, turn_angles
from affnerf.grasp.gripper import grasp_pose
from affnerf.grasp.physics import LiftConfig, lift_test

X, Y, Z = np.eye(3)
BOX = trimesh.creation.box(extents=[0.04, 0.04, 0.12])
ROD = trimesh.creation.box(extents=[0.25, 0.02, 0.02])  # long along x


def test_centred_grasp_across_a_box_survives_the_disturbance():
    pose = grasp_pose(np.zeros(3), X, Y)
    lift, dist = lift_and_disturb(BOX, pose, 0.04)
    assert lift == lift_test(BOX, pose, 0.04) and lift.success  # the lift is the plain lift test
    assert dist is not None and dist.held and dist.fingers == 2 and dist.drift < 0.002 and dist.turn < 1.0


@pytest.mark.parametrize("x, held", [(0.08, True), (0.115, False)], ids=["inboard", "at-the-end"])
def test_rod_on_low_friction_lifts_but_turns_out_when_held_at_its_end(x, held):
    config = replace(LiftConfig(), object_friction=0.3)
    lift, dist = lift_and_disturb(ROD, grasp_pose(np.array([x, 0.0, 0.0]), Y, -Z), 0.02, config=config)
    assert lift.success and dist is not None
    assert dist.held is held
    if not held:
        assert dist.turn > DisturbConfig().turn_tolerance_deg or dist.drift > DisturbConfig().drift_tolerance


def test_failed_lift_is_not_disturbed():
    lift, dist = lift_and_disturb(BOX, grasp_pose(np.array([0.1, 0.0, 0.0]), X, Y), 0.04)
    assert not lift.success and dist is None


def test_disturbance_paths():
    config = DisturbConfig(angle_deg=90.0, turn_time=0.5, shake_amplitude=0.02, shake_frequency=2.0)
    angles = turn_angles(config, 1 / 240)
    assert len(angles) == 4 * 120 and angles.max() == pytest.approx(90.0) and angles.min() == pytest.approx(-90.0)
    assert angles[-1] == pytest.approx(0.0, abs=1e-9)
    shake = shake_offsets(config, 1 / 240)
    assert shake.shape == (3 * 120, 3) and np.abs(shake).max() == pytest.approx(0.02, abs=1e-4)
    assert np.count_nonzero(np.abs(shake).max(axis=0) > 0.019) == 3 and np.allclose(shake[-1], 0.0, atol=1e-9)
