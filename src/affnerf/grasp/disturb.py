"""Lift-and-disturb (conventions §6): after a successful lift test, the gripper turns the object +90° and -90°
about its closing axis and shakes it along each world axis; success if it is still held where it was.

Protocol of :func:`disturb`, following step 5 of :mod:`affnerf.grasp.physics` in the same simulation (gravity
on): turn from 0 to +``angle_deg`` about the grasp's closing axis (through the grasp centre), then to
-``angle_deg``, then back to 0, each quarter in ``turn_time`` on a cosine ramp; then shake one period of a
sinusoid of ``shake_amplitude`` at ``shake_frequency`` along world x, y and z in turn. Success: both fingers
still touch the object, and in the gripper's frame its centre of mass moved less than ``drift_tolerance`` and it
turned less than ``turn_tolerance_deg`` since the start of the disturbance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.physics import LiftConfig, LiftResult, Rig, simulate


@dataclass(frozen=True)
class DisturbConfig:
    """Settings of the disturbance, in SI units (degrees for angles)."""

    angle_deg: float = 90.0  #: turned to +angle and -angle about the closing axis
    turn_time: float = 0.5  #: duration of each quarter of the turn (0 -> +angle, +angle -> 0, ...)
    shake_amplitude: float = 0.02  #: peak displacement of the shake (m)
    shake_frequency: float = 2.0  #: shake frequency (Hz); one period per world axis
    drift_tolerance: float = 0.01  #: largest motion of the centre of mass in the gripper's frame (m)
    turn_tolerance_deg: float = 15.0  #: largest turn of the object in the gripper's frame


@dataclass(frozen=True)
class DisturbResult:
    """``held``: still held after the disturbance; ``drift`` (m) and ``turn`` (degrees): how far the object moved
    and turned in the gripper's frame; ``fingers``: how many fingers touched it at the end."""

    held: bool
    drift: float
    turn: float
    fingers: int


def _relative(rig: Rig) -> tuple[np.ndarray, Rotation]:
    """The object's centre of mass and orientation in the gripper's frame."""
    gp, gq = rig.client.getBasePositionAndOrientation(rig.grip)
    op, oq = rig.client.getBasePositionAndOrientation(rig.obj)
    g = Rotation.from_quat(gq)
    return g.inv().apply(np.asarray(op) - np.asarray(gp)), g.inv() * Rotation.from_quat(oq)


def turn_angles(config: DisturbConfig, time_step: float) -> np.ndarray:
    """(N,) angle (degrees) about the closing axis at each step: 0 -> +a -> 0 -> -a -> 0 on cosine ramps.

    >>> a = turn_angles(DisturbConfig(angle_deg=90.0, turn_time=0.5), 0.25)
    >>> (a.round(6) + 0.0).tolist()
    [45.0, 90.0, 45.0, 0.0, -45.0, -90.0, -45.0, 0.0]
    """
    n = max(1, int(round(config.turn_time / time_step)))
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(1, n + 1) / n)
    a = config.angle_deg
    return np.concatenate([a * ramp, a * (1 - ramp), -a * ramp, -a * (1 - ramp)])


def shake_offsets(config: DisturbConfig, time_step: float) -> np.ndarray:
    """(N, 3) displacement at each step: one sinusoid period along world x, then y, then z."""
    n = max(1, int(round(1.0 / (config.shake_frequency * time_step))))
    wave = config.shake_amplitude * np.sin(2.0 * np.pi * np.arange(1, n + 1) / n)
    return np.concatenate([wave[:, None] * axis[None] for axis in np.eye(3)])


def disturb(rig: Rig, held_at: np.ndarray, pose: np.ndarray, config: DisturbConfig) -> DisturbResult:
    """Turn and shake the held object (module docstring); ``held_at`` (3,) is where the grasp centre is held and
    ``pose`` (4, 4) the grasp (its rotation is the gripper's at rest)."""
    step = rig.config.time_step
    start_pos, start_rot = _relative(rig)
    axis = pose[:3, 0] / np.linalg.norm(pose[:3, 0])
    for angle in turn_angles(config, step):
        turn = Rotation.from_rotvec(np.radians(angle) * axis).as_matrix()
        rig.orientation = Rotation.from_matrix(turn @ pose[:3, :3]).as_quat().tolist()
        rig.move(held_at)
    for offset in shake_offsets(config, step):
        rig.move(held_at + offset)
    end_pos, end_rot = _relative(rig)
    drift = float(np.linalg.norm(end_pos - start_pos))
    turned = float(np.degrees((start_rot.inv() * end_rot).magnitude()))
    fingers = rig.touching()
    held = fingers == 2 and drift < config.drift_tolerance and turned < config.turn_tolerance_deg
    return DisturbResult(held, drift, turned, fingers)


def lift_and_disturb(
    mesh: trimesh.Trimesh,
    pose: np.ndarray,
    width: float,
    gripper: ParallelJawGripper = ParallelJawGripper(),
    config: LiftConfig | None = None,
    disturbance: DisturbConfig = DisturbConfig(),
) -> tuple[LiftResult, DisturbResult | None]:
    """The lift test (``config``: :class:`LiftConfig`'s defaults when None), then (after a successful lift) the
    disturbance; None for a failed lift."""
    pose, config = np.asarray(pose, float), config or LiftConfig()
    return simulate(mesh, pose, width, gripper, config, lambda rig, at: disturb(rig, at, pose, disturbance))
