"""A physics lift test for parallel-jaw grasps (conventions §6) in pybullet's headless DIRECT mode.

Protocol of :func:`lift_test`, in a fresh pybullet client per call that is always disconnected afterwards:

1. The object sits where its mesh frame says (world = mesh frame, +z up: gravity acts along -z). Its collision
   shape is a convex decomposition of the mesh (:func:`convex_parts`, CoACD); its mass, inertia, friction and
   restitution come from :class:`LiftConfig`, never from pybullet's defaults.
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

import hashlib
import os
import tempfile
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import pybullet
import trimesh
from pybullet_utils.bullet_client import BulletClient
from scipy.spatial.transform import Rotation

from affnerf.errors import AffnerfError
from affnerf.grasp.gripper import ParallelJawGripper

FINGER_LINKS = (0, 1)  #: pybullet link indices of finger 1 (at -x of the grasp frame) and finger 2 (at +x)
_MAX_PIECES = 256  #: meshes with more connected pieces than this are decomposed as a whole
_CACHE_SIZE = 64  #: decompositions kept by :func:`convex_parts`
_CACHE: OrderedDict[str, tuple[trimesh.Trimesh, ...]] = OrderedDict()


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
        positive = ("mass", "gripping_force", "finger_speed", "finger_mass", "palm_mass", "drive_force",
                    "approach_time", "close_time", "lift_time", "time_step", "solver_iterations")
        bad = {name for name in positive if not getattr(self, name) > 0}
        bad |= {name for name, value in vars(self).items() if not (np.isfinite(value) and value >= 0)}
        if bad:
            raise AffnerfError(f"lift test config: {', '.join(sorted(bad))} out of range (all are finite and"
                               " non-negative; masses, forces, speeds, durations and iterations positive)")


@dataclass(frozen=True)
class LiftResult:
    """Outcome of one lift test: ``success``; ``lifted``, how far (m) the object's centre of mass rose from the
    start of the lift to the end of the hold; ``held``, both fingers touched it at the end; ``reason``, one of
    "ok", "collision at start", "collision on approach", "no contact", "dropped", "slipped"."""

    success: bool
    lifted: float
    held: bool
    reason: str


def convex_parts(mesh: trimesh.Trimesh, threshold: float = 0.08, max_parts: int = 16) -> list[trimesh.Trimesh]:
    """Convex decomposition of ``mesh`` (metres; closed or open, possibly a union of parts) with CoACD, cached
    per mesh content and settings; returns convex meshes in the mesh frame (copies, safe to modify).

    When every connected piece is closed (as given, or after merging duplicate vertices), each piece is
    decomposed on its own, else the mesh as a whole (CoACD remeshes it). A piece that is nearly convex, small or
    that CoACD fails on becomes its convex hull; flat pieces are dropped. A typical object (0.1-0.44 m, a few
    thousand faces) takes well under a few seconds, a large thin-walled one (30k faces) ten or more.

    Args:
        mesh: the mesh.
        threshold: CoACD's concavity threshold, relative to a piece's size (larger: fewer, coarser parts).
        max_parts: at most this many convex parts per piece.

    Raises:
        AffnerfError: the mesh is empty, has non-finite vertices, or encloses no volume at all.
    """
    if len(mesh.faces) == 0 or not np.all(np.isfinite(mesh.vertices)):
        raise AffnerfError("lift test: the mesh is empty or has non-finite vertices")
    digest = hashlib.sha1(np.ascontiguousarray(mesh.vertices, np.float64).tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, np.int64).tobytes())
    key = f"{digest.hexdigest()}:{threshold}:{max_parts}"
    if key not in _CACHE:
        _CACHE[key] = tuple(_decompose(mesh, threshold, max_parts))
        if len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    _CACHE.move_to_end(key)
    return [part.copy() for part in _CACHE[key]]


def _decompose(mesh: trimesh.Trimesh, threshold: float, max_parts: int) -> list[trimesh.Trimesh]:
    """Uncached body of :func:`convex_parts`."""
    pieces = [mesh]
    merged = mesh.copy()
    merged.merge_vertices()
    for candidate in (mesh, merged):
        split = candidate.split(only_watertight=False)
        if 0 < len(split) <= _MAX_PIECES and all(piece.is_watertight for piece in split):
            pieces = split
            break
    size = float(np.max(mesh.extents))
    parts = [part for piece in pieces for part in _decompose_piece(piece, threshold, max_parts, size)]
    if not parts:
        raise AffnerfError("lift test: the mesh encloses no volume")
    return parts


def _hull(vertices: np.ndarray) -> trimesh.Trimesh | None:
    """Convex hull of points, or None when they are flat or degenerate."""
    try:
        with np.errstate(divide="ignore", invalid="ignore"):
            hull = trimesh.Trimesh(vertices=np.asarray(vertices, float)).convex_hull
            return hull if hull.volume > 0.0 else None
    except Exception:  # noqa: BLE001 - qhull rejects flat or tiny point sets
        return None


def _decompose_piece(piece: trimesh.Trimesh, threshold: float, max_parts: int, size: float) -> list[trimesh.Trimesh]:
    """Convex parts of one piece: its hull when it nearly fills it, is under 5% of ``size`` or CoACD fails."""
    hull = _hull(piece.vertices)
    if hull is None:
        return []
    convex = piece.is_volume and piece.volume >= 0.98 * hull.volume
    if convex or len(piece.faces) < 8 or np.max(piece.extents) < 0.05 * size:
        return [hull]
    try:
        import coacd

        coacd.set_log_level("error")
        raw = coacd.run_coacd(
            coacd.Mesh(np.asarray(piece.vertices, np.float64), np.asarray(piece.faces, np.int32)),
            threshold=threshold, max_convex_hull=max_parts, preprocess_mode="auto", preprocess_resolution=40,
            resolution=1000, mcts_nodes=10, mcts_iterations=30, mcts_max_depth=2, seed=0,
        )
    except Exception:  # noqa: BLE001 - any CoACD failure falls back to the hull
        return [hull]
    parts = [part for part in (_hull(vertices) for vertices, _ in raw if len(vertices) >= 4) if part is not None]
    return parts or [hull]


def mass_properties(parts: list[trimesh.Trimesh], mass: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre of mass (3,), principal moments of inertia (3,) and principal axes (3x3 rotation, as columns) of a
    uniform solid of ``mass`` filling the convex ``parts`` (where parts overlap, they count twice)."""
    solid = trimesh.util.concatenate(parts)
    if not solid.volume > 0.0:
        raise AffnerfError("lift test: the mesh encloses no volume")
    moments, axes = np.linalg.eigh(solid.moment_inertia * (mass / solid.volume))
    if np.linalg.det(axes) < 0.0:
        axes[:, 0] = -axes[:, 0]
    return np.asarray(solid.center_mass, float), np.maximum(moments, 1e-12), axes


def _quat(rotation: np.ndarray) -> list[float]:
    """pybullet quaternion (x, y, z, w) of a 3x3 rotation."""
    return Rotation.from_matrix(rotation).as_quat().tolist()


def _set_surface(client: BulletClient, body: int, link: int, friction: float, config: LiftConfig) -> None:
    """Set every surface and damping property of one link explicitly."""
    client.changeDynamics(body, link, lateralFriction=friction, spinningFriction=config.spinning_friction,
                          rollingFriction=config.rolling_friction, restitution=config.restitution,
                          linearDamping=0.0, angularDamping=0.0)


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
    body = client.createMultiBody(baseMass=config.mass, baseCollisionShapeIndex=shape, basePosition=[0, 0, 0],
                                  baseInertialFramePosition=com.tolist(), baseInertialFrameOrientation=_quat(axes))
    client.changeDynamics(body, -1, localInertiaDiagonal=moments.tolist())
    _set_surface(client, body, -1, config.object_friction, config)
    return body


def add_gripper(client: BulletClient, gripper: ParallelJawGripper, opening: float, pose: np.ndarray,
                config: LiftConfig) -> int:
    """Add the floating gripper opened to ``opening``, its base frame (the grasp frame, also its centre of mass)
    at ``pose``; returns its body id. Links :data:`FINGER_LINKS` are the fingers, whose joint positions are how
    far each has moved inwards; a gear constraint keeps them equal."""
    (c1, h1), (c2, h2), (cp, hp) = gripper.boxes(opening)
    palm = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=hp.tolist(), collisionFramePosition=cp.tolist())
    fingers = [client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=h.tolist()) for h in (h1, h2)]
    body = client.createMultiBody(
        baseMass=config.palm_mass, baseCollisionShapeIndex=palm, basePosition=pose[:3, 3].tolist(),
        baseOrientation=_quat(pose[:3, :3]), linkMasses=[config.finger_mass] * 2,
        linkCollisionShapeIndices=fingers, linkVisualShapeIndices=[-1, -1], linkPositions=[c1.tolist(), c2.tolist()],
        linkOrientations=[[0, 0, 0, 1]] * 2, linkInertialFramePositions=[[0, 0, 0]] * 2,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * 2, linkParentIndices=[0, 0],
        linkJointTypes=[pybullet.JOINT_PRISMATIC] * 2, linkJointAxis=[[1, 0, 0], [-1, 0, 0]],
    )
    for link in (-1, *FINGER_LINKS):
        _set_surface(client, body, link, config.finger_friction, config)
    gear = client.createConstraint(body, FINGER_LINKS[0], body, FINGER_LINKS[1], pybullet.JOINT_GEAR,
                                   jointAxis=[1, 0, 0], parentFramePosition=[0, 0, 0], childFramePosition=[0, 0, 0])
    client.changeConstraint(gear, gearRatio=-1.0, erp=0.2, maxForce=config.drive_force)
    return body


def _touching(client: BulletClient, obj: int, grip: int, config: LiftConfig) -> int:
    """How many fingers touch the object (0, 1 or 2)."""
    tol = config.contact_tolerance
    return sum(any(p[8] < tol for p in client.getClosestPoints(obj, grip, tol, linkIndexA=-1, linkIndexB=link))
               for link in FINGER_LINKS)


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


def lift_test(mesh: trimesh.Trimesh, pose: np.ndarray, width: float,
              gripper: ParallelJawGripper = ParallelJawGripper(), config: LiftConfig = LiftConfig()) -> LiftResult:
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
    pose = _checked_pose(pose, width, gripper)
    parts = convex_parts(mesh)
    opening = min(width + config.open_margin, gripper.max_opening)
    client = BulletClient(connection_mode=pybullet.DIRECT)
    try:
        client.setPhysicsEngineParameter(fixedTimeStep=config.time_step, numSolverIterations=config.solver_iterations,
                                         numSubSteps=0, deterministicOverlappingPairs=1)
        client.setGravity(0.0, 0.0, 0.0)
        obj = add_object(client, parts, config)
        start = pose[:3, 3] - config.approach_distance * pose[:3, 2]
        grip = add_gripper(client, gripper, opening, np.block([[pose[:3, :3], start[:, None]], [pose[3:]]]), config)
        return _run(client, obj, grip, pose, start, opening, config)
    finally:
        client.disconnect()


def _run(client: BulletClient, obj: int, grip: int, pose: np.ndarray, start: np.ndarray, opening: float,
         config: LiftConfig) -> LiftResult:
    """Steps 2-5 of the protocol; the gripper stands at ``start``, the object at rest."""
    client.performCollisionDetection()
    if any(p[8] < -config.penetration_tolerance for p in client.getClosestPoints(obj, grip, 0.0)):
        return LiftResult(False, 0.0, False, "collision at start")
    orientation = _quat(pose[:3, :3])
    drive = client.createConstraint(grip, -1, -1, -1, pybullet.JOINT_FIXED, jointAxis=[0, 0, 0],
                                    parentFramePosition=[0, 0, 0], childFramePosition=start.tolist(),
                                    childFrameOrientation=orientation)

    def fingers(target: float) -> None:
        for link in FINGER_LINKS:
            client.setJointMotorControl2(grip, link, pybullet.POSITION_CONTROL, targetPosition=target,
                                         force=config.gripping_force, maxVelocity=config.finger_speed)

    def move(target: np.ndarray) -> None:
        client.changeConstraint(drive, jointChildPivot=target.tolist(), jointChildFrameOrientation=orientation,
                                maxForce=config.drive_force)
        client.stepSimulation()

    def object_position() -> np.ndarray:
        return np.asarray(client.getBasePositionAndOrientation(obj)[0])

    initial = object_position()
    fingers(0.0)  # held open
    for s in _ramp(config.approach_time, config):
        move(start + s * (pose[:3, 3] - start))
    if np.linalg.norm(object_position() - initial) > config.approach_tolerance:
        return LiftResult(False, 0.0, False, "collision on approach")
    fingers(opening / 2.0)  # the pads would meet at the grasp centre
    for _ in _ramp(config.close_time, config):
        move(pose[:3, 3])
    if _touching(client, obj, grip, config) < 2:
        return LiftResult(False, 0.0, False, "no contact")
    client.setGravity(0.0, 0.0, -config.gravity)
    before = object_position()
    up = np.array([0.0, 0.0, config.lift_height])
    for s in _ramp(config.lift_time, config):
        move(pose[:3, 3] + s * up)
    for _ in _ramp(config.hold_time, config):
        move(pose[:3, 3] + up)
    lifted = float(object_position()[2] - before[2])
    if _touching(client, obj, grip, config) < 2:
        return LiftResult(False, lifted, False, "dropped")
    if lifted < config.success_fraction * config.lift_height:
        return LiftResult(False, lifted, True, "slipped")
    return LiftResult(True, lifted, True, "ok")
