"""A physics lift test for parallel-jaw grasps (conventions §6) in pybullet's headless DIRECT mode.

Protocol of :func:`lift_test`, in a fresh pybullet client per call that is always disconnected afterwards:

1. The object sits where its mesh frame says (world = mesh frame, +z up: gravity acts along -z). Its collision
   shape is a convex decomposition of the mesh (:func:`affnerf.grasp.convex.convex_parts`, CoACD); its mass,
   inertia, friction and restitution come from :class:`LiftConfig`, never from pybullet's defaults.
2. A floating gripper, the boxes of :meth:`ParallelJawGripper.boxes` (a palm and two fingers on prismatic
   joints geared to move together), opened to ``min(width + open_margin, max_opening)``, starts
   ``approach_distance`` back along the grasp's -z. If it overlaps the object there: ``"collision at start"``.
3. Gravity is off while the gripper moves along +z onto the grasp pose. The object floats, so a gripper that
   bumps into it pushes it away; moved by more than ``approach_tolerance``: ``"collision on approach"``.
4. The fingers close under position control with at most ``gripping_force`` each, for ``close_time``. Unless
   both fingers then touch the object: ``"no contact"``.
5. Gravity comes on; the gripper rises ``lift_height`` along world +z in ``lift_time`` and holds still for
   ``hold_time``. Success (``"ok"``): both fingers still touch the object and its centre of mass rose at least
   ``success_fraction * lift_height``; otherwise ``"dropped"`` (fewer than two fingers touch it) or
   ``"slipped"`` (still held, but it slid or turned down between the fingers).

The gripper's base is driven by a fixed constraint to the world whose target moves every step along a cosine
ramp (``changeConstraint``). Bullet multiplies two bodies' lateral frictions, so pad-object friction is
``object_friction * finger_friction``; spinning and rolling friction combine as ``s_a * mu_b + s_b * mu_a``.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import pybullet
import trimesh
from pybullet_utils.bullet_client import BulletClient
from scipy.spatial.transform import Rotation

from affnerf.errors import AffnerfError
from affnerf.grasp.convex import convex_parts, mass_properties
from affnerf.grasp.gripper import ParallelJawGripper

FINGER_LINKS = (0, 1)  #: pybullet link indices of finger 1 (at -x of the grasp frame) and finger 2 (at +x)


@dataclass(frozen=True)
class LiftConfig:
    """Settings of the lift test, in SI units (metres, kilograms, seconds, newtons)."""

    mass: float = 0.1  #: mass of the object
    object_friction: float = 0.8  #: lateral (Coulomb) friction coefficient of the object
    finger_friction: float = 1.0  #: lateral friction coefficient of the fingers and palm
    spinning_friction: float = 0.002  #: Bullet's torsional friction (m), of the object and every gripper link
    rolling_friction: float = 0.0001  #: Bullet's rolling friction (m), of the object and every gripper link
    restitution: float = 0.0  #: bounciness of every body (0: contacts do not bounce)
    gripping_force: float = 20.0  #: largest force of each finger's motor, closing and holding
    finger_speed: float = 0.1  #: largest closing speed of each finger
    finger_mass: float = 0.02  #: mass of each finger
    palm_mass: float = 0.3  #: mass of the palm, the gripper's floating base
    drive_force: float = 1000.0  #: largest force of the constraints that move the gripper and gear its fingers
    open_margin: float = 0.02  #: the fingers start opened to min(width + open_margin, max_opening)
    approach_distance: float = 0.05  #: how far back along the grasp's -z the gripper starts
    approach_time: float = 0.5  #: duration of the approach onto the grasp pose
    close_time: float = 0.4  #: how long the fingers close, long enough to close fully at finger_speed
    lift_height: float = 0.10  #: how far the gripper rises along world +z
    lift_time: float = 0.5  #: duration of the lift
    hold_time: float = 1.0  #: how long the gripper holds still after the lift
    time_step: float = 1.0 / 240.0  #: simulation time step
    gravity: float = 9.81  #: gravitational acceleration along world (= mesh frame) -z, from the lift on
    solver_iterations: int = 200  #: solver iterations per step (at Bullet's default, 50, held objects creep)
    success_fraction: float = 0.8  #: the object must rise at least this share of lift_height
    contact_tolerance: float = 0.002  #: a finger touches the object when closer than this
    penetration_tolerance: float = 0.001  #: the start pose collides when the gripper is deeper in the object
    approach_tolerance: float = 0.005  #: the approach collided when it moved the object further than this

    def __post_init__(self) -> None:
        positive = (
            "mass",
            "gripping_force",
            "finger_speed",
            "finger_mass",
            "palm_mass",
            "drive_force",
            "approach_time",
            "close_time",
            "lift_time",
            "time_step",
            "solver_iterations",
        )
        bad = {name for name in positive if not getattr(self, name) > 0}
        bad |= {name for name, value in vars(self).items() if not (np.isfinite(value) and value >= 0)}
        if bad:
            raise AffnerfError(
                f"lift test config: {', '.join(sorted(bad))} out of range (all are finite and"
                " non-negative; masses, forces, speeds, durations and iterations positive)"
            )


@dataclass(frozen=True)
class LiftResult:
    """Outcome of one lift test: ``success``; ``lifted``, how far (m) the object's centre of mass rose from the
    start of the lift to the end of the hold; ``held``, both fingers touched it at the end; ``reason``, one of
    "ok", "collision at start", "collision on approach", "no contact", "dropped", "slipped"."""

    success: bool
    lifted: float
    held: bool
    reason: str


def _quat(rotation: np.ndarray) -> list[float]:
    """pybullet quaternion (x, y, z, w) of a 3x3 rotation."""
    return Rotation.from_matrix(rotation).as_quat().tolist()


def _set_surface(client: BulletClient, body: int, link: int, friction: float, config: LiftConfig) -> None:
    """Set every surface and damping property of one link explicitly."""
    client.changeDynamics(
        body,
        link,
        lateralFriction=friction,
        spinningFriction=config.spinning_friction,
        rollingFriction=config.rolling_friction,
        restitution=config.restitution,
        linearDamping=0.0,
        angularDamping=0.0,
    )


def add_object(client: BulletClient, parts: list[trimesh.Trimesh], config: LiftConfig) -> int:
    """Add the object, one dynamic body made of the convex ``parts``, its mesh frame at the world frame;
    returns its body id. pybullet reports its position as that of its centre of mass."""
    com, moments, axes = mass_properties(parts, config.mass)
    if len(parts) == 1:
        shape = client.createCollisionShape(pybullet.GEOM_MESH, vertices=parts[0].vertices.tolist())
    else:  # pybullet makes a compound of one convex hull per object ("o") of an OBJ file
        lines, offset = [], 1
        for i, part in enumerate(parts):
            lines += [f"o part{i}", *(f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in part.vertices)]
            lines += [f"f {a + offset} {b + offset} {c + offset}" for a, b, c in part.faces]
            offset += len(part.vertices)
        with tempfile.TemporaryDirectory(prefix="affnerf-lift-") as folder:
            path = os.path.join(folder, "parts.obj")
            with open(path, "w") as f:
                f.write("\n".join(lines) + "\n")
            shape = client.createCollisionShape(pybullet.GEOM_MESH, fileName=path)
    body = client.createMultiBody(
        baseMass=config.mass,
        baseCollisionShapeIndex=shape,
        basePosition=[0, 0, 0],
        baseInertialFramePosition=com.tolist(),
        baseInertialFrameOrientation=_quat(axes),
    )
    client.changeDynamics(body, -1, localInertiaDiagonal=moments.tolist())
    _set_surface(client, body, -1, config.object_friction, config)
    return body


def add_gripper(
    client: BulletClient, gripper: ParallelJawGripper, opening: float, pose: np.ndarray, config: LiftConfig
) -> int:
    """Add the floating gripper opened to ``opening``, its base frame (the grasp frame, also its centre of mass)
    at ``pose``; returns its body id. Links :data:`FINGER_LINKS` are the fingers, whose joint positions are how
    far each has moved inwards; a gear constraint keeps them equal."""
    (c1, h1), (c2, h2), (cp, hp) = gripper.boxes(opening)
    palm = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=hp.tolist(), collisionFramePosition=cp.tolist())
    fingers = [client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=h.tolist()) for h in (h1, h2)]
    body = client.createMultiBody(
        baseMass=config.palm_mass,
        baseCollisionShapeIndex=palm,
        basePosition=pose[:3, 3].tolist(),
        baseOrientation=_quat(pose[:3, :3]),
        linkMasses=[config.finger_mass] * 2,
        linkCollisionShapeIndices=fingers,
        linkVisualShapeIndices=[-1, -1],
        linkPositions=[c1.tolist(), c2.tolist()],
        linkOrientations=[[0, 0, 0, 1]] * 2,
        linkInertialFramePositions=[[0, 0, 0]] * 2,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * 2,
        linkParentIndices=[0, 0],
        linkJointTypes=[pybullet.JOINT_PRISMATIC] * 2,
        linkJointAxis=[[1, 0, 0], [-1, 0, 0]],
    )
    for link in (-1, *FINGER_LINKS):
        _set_surface(client, body, link, config.finger_friction, config)
    gear = client.createConstraint(
        body,
        FINGER_LINKS[0],
        body,
        FINGER_LINKS[1],
        pybullet.JOINT_GEAR,
        jointAxis=[1, 0, 0],
        parentFramePosition=[0, 0, 0],
        childFramePosition=[0, 0, 0],
    )
    client.changeConstraint(gear, gearRatio=-1.0, erp=0.2, maxForce=config.drive_force)
    return body


def _touching(client: BulletClient, obj: int, grip: int, config: LiftConfig) -> int:
    """How many fingers touch the object (0, 1 or 2)."""
    tol = config.contact_tolerance
    return sum(
        any(p[8] < tol for p in client.getClosestPoints(obj, grip, tol, linkIndexA=-1, linkIndexB=link))
        for link in FINGER_LINKS
    )


def _ramp(duration: float, config: LiftConfig) -> np.ndarray:
    """Share of a path done after each step of ``duration``: a cosine ramp from 0 to 1, so the gripper starts and
    stops without a jerk (peak acceleration pi^2/2 * distance / duration^2)."""
    n = max(1, int(round(duration / config.time_step)))
    return 0.5 - 0.5 * np.cos(np.pi * np.arange(1, n + 1) / n)


def _checked_pose(pose: np.ndarray, width: float, gripper: ParallelJawGripper) -> np.ndarray:
    """The grasp pose as a float (4, 4) array, after checking it and the width."""
    pose = np.asarray(pose, dtype=float)
    if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
        raise AffnerfError(f"lift test: the grasp pose must be a finite 4x4 matrix, got shape {pose.shape}")
    rotation = pose[:3, :3]
    if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-4) or np.linalg.det(rotation) < 0.0:
        raise AffnerfError("lift test: the grasp pose's rotation is not a rotation matrix")
    if not (np.isfinite(width) and 0.0 <= width <= gripper.max_opening + 1e-9):
        raise AffnerfError(f"lift test: grasp width {width} is outside [0, {gripper.max_opening}]")
    return pose


def lift_test(
    mesh: trimesh.Trimesh,
    pose: np.ndarray,
    width: float,
    gripper: ParallelJawGripper = ParallelJawGripper(),
    config: LiftConfig = LiftConfig(),
) -> LiftResult:
    """Approach, close on, lift (10 cm) and hold (1 s) ``mesh`` with ``gripper`` in pybullet (module docstring).

    Deterministic, and independent of other calls but for the cached decomposition (:func:`convex_parts`).

    Args:
        mesh: the object in metres, +z up: gravity acts along its frame's -z.
        pose: the (4, 4) grasp pose in the mesh frame (the grasp frame of ``gripper.py``).
        width: the grasp's opening width (the object's thickness between the pads).
        gripper: the gripper's dimensions.
        config: masses, frictions, forces, timings and tolerances.

    Raises:
        AffnerfError: a malformed pose or width, or a mesh that is empty or encloses no volume.
    """
    return simulate(mesh, pose, width, gripper, config)[0]


def simulate(
    mesh: trimesh.Trimesh,
    pose: np.ndarray,
    width: float,
    gripper: ParallelJawGripper = ParallelJawGripper(),
    config: LiftConfig = LiftConfig(),
    after: Callable[[Rig, np.ndarray], Any] | None = None,
) -> tuple[LiftResult, Any]:
    """:func:`lift_test`, then, after a successful lift, ``after(rig, held_at)`` with the simulation still
    running (``held_at``: where the grasp centre is held, (3,)); returns the lift's result and ``after``'s (None
    when it did not run)."""
    pose = _checked_pose(pose, width, gripper)
    parts = convex_parts(mesh)
    opening = min(width + config.open_margin, gripper.max_opening)
    with _c_stdout_silenced():  # pybullet prints "argv[0]=" from C on every connection
        client = BulletClient(connection_mode=pybullet.DIRECT)
    try:
        client.setPhysicsEngineParameter(
            fixedTimeStep=config.time_step,
            numSolverIterations=config.solver_iterations,
            numSubSteps=0,
            deterministicOverlappingPairs=1,
        )
        client.setGravity(0.0, 0.0, 0.0)
        obj = add_object(client, parts, config)
        start = pose[:3, 3] - config.approach_distance * pose[:3, 2]
        grip = add_gripper(client, gripper, opening, np.block([[pose[:3, :3], start[:, None]], [pose[3:]]]), config)
        result, rig = _run(client, obj, grip, pose, start, opening, config)
        if after is None or not result.success or rig is None:
            return result, None
        return result, after(rig, pose[:3, 3] + np.array([0.0, 0.0, config.lift_height]))
    finally:
        client.disconnect()


@contextlib.contextmanager
def _c_stdout_silenced() -> Iterator[None]:
    """Route what C code prints to the process's standard output (file descriptor 1) to the null device for the
    block; Python's ``sys.stdout`` is flushed first and C's buffer before it is restored, so nothing crosses over."""
    sys.stdout.flush()
    saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        yield
    finally:
        ctypes.CDLL(None).fflush(None)
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


@dataclass
class Rig:
    """The simulated gripper driven by a fixed constraint, its fingers, and the object it acts on."""

    client: BulletClient
    obj: int
    grip: int
    drive: int
    orientation: list[float]
    config: LiftConfig

    @classmethod
    def attach(cls, client: BulletClient, obj: int, grip: int, pose: np.ndarray, start: np.ndarray, config: LiftConfig):
        """Fix the gripper at ``start`` with the orientation of ``pose`` through a constraint that will drive it."""
        orientation = _quat(pose[:3, :3])
        drive = client.createConstraint(
            grip, -1, -1, -1, pybullet.JOINT_FIXED, jointAxis=[0, 0, 0], parentFramePosition=[0, 0, 0],
            childFramePosition=start.tolist(), childFrameOrientation=orientation,
        )  # fmt: skip
        return cls(client, obj, grip, drive, orientation, config)

    def fingers(self, target: float) -> None:
        """Drive both fingers towards ``target`` (metres from the open position) with bounded force and speed."""
        for link in FINGER_LINKS:
            self.client.setJointMotorControl2(
                self.grip, link, pybullet.POSITION_CONTROL, targetPosition=target,
                force=self.config.gripping_force, maxVelocity=self.config.finger_speed,
            )  # fmt: skip

    def move(self, target: np.ndarray) -> None:
        """One simulation step with the gripper pulled towards ``target``."""
        self.client.changeConstraint(
            self.drive,
            jointChildPivot=target.tolist(),
            jointChildFrameOrientation=self.orientation,
            maxForce=self.config.drive_force,
        )
        self.client.stepSimulation()

    def object_position(self) -> np.ndarray:
        return np.asarray(self.client.getBasePositionAndOrientation(self.obj)[0])

    def touching(self) -> int:
        return _touching(self.client, self.obj, self.grip, self.config)


def _run(
    client: BulletClient, obj: int, grip: int, pose: np.ndarray, start: np.ndarray, opening: float, config: LiftConfig
) -> tuple[LiftResult, Rig | None]:
    """Steps 2-5 of the protocol; the gripper stands at ``start``, the object at rest. Returns the result and the
    rig (None when it never got attached)."""
    client.performCollisionDetection()
    if any(p[8] < -config.penetration_tolerance for p in client.getClosestPoints(obj, grip, 0.0)):
        return LiftResult(False, 0.0, False, "collision at start"), None
    rig = Rig.attach(client, obj, grip, pose, start, config)
    initial = rig.object_position()
    rig.fingers(0.0)  # held open
    for s in _ramp(config.approach_time, config):
        rig.move(start + s * (pose[:3, 3] - start))
    if np.linalg.norm(rig.object_position() - initial) > config.approach_tolerance:
        return LiftResult(False, 0.0, False, "collision on approach"), rig
    rig.fingers(opening / 2.0)  # the pads would meet at the grasp centre
    for _ in _ramp(config.close_time, config):
        rig.move(pose[:3, 3])
    if rig.touching() < 2:
        return LiftResult(False, 0.0, False, "no contact"), rig
    return _lift_and_hold(rig, pose[:3, 3]), rig


def _lift_and_hold(rig: Rig, grasp_centre: np.ndarray) -> LiftResult:
    """Steps 4-5: gravity on, lift by ``lift_height``, hold, and judge whether the object came along."""
    config = rig.config
    rig.client.setGravity(0.0, 0.0, -config.gravity)
    before = rig.object_position()
    up = np.array([0.0, 0.0, config.lift_height])
    for s in _ramp(config.lift_time, config):
        rig.move(grasp_centre + s * up)
    for _ in _ramp(config.hold_time, config):
        rig.move(grasp_centre + up)
    lifted = float(rig.object_position()[2] - before[2])
    if rig.touching() < 2:
        return LiftResult(False, lifted, False, "dropped")
    if lifted < config.success_fraction * config.lift_height:
        return LiftResult(False, lifted, True, "slipped")
    return LiftResult(True, lifted, True, "ok")
