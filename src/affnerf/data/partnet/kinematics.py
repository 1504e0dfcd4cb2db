"""Forward kinematics of a parsed URDF: joint values for a state mode, and the world pose of every link.

URDF semantics: ``world(child) = world(parent) @ origin @ motion(q)``, where ``motion`` rotates about the joint
axis through the joint frame's origin (revolute, continuous) or slides along it (prismatic). Root links (children
of no joint) sit at the identity.
"""

from __future__ import annotations

import numpy as np

from affnerf.data.partnet.urdf import Joint, Urdf
from affnerf.errors import AffnerfError, input_error

#: Joint state modes: ``rest`` is 0 clamped into the limits (the pose as modelled); ``random`` is uniform within
#: the limits (continuous joints: uniform in [0, 2 pi)).
JOINT_STATE_MODES: tuple[str, ...] = ("rest", "random")

#: Joints that move (and whose state is recorded).
MOVING_TYPES: tuple[str, ...] = ("revolute", "prismatic", "continuous")


def axis_angle_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` radians about the unit ``axis`` (3,) (Rodrigues' formula).

    Example:
        >>> np.round(axis_angle_matrix(np.array([0.0, 0.0, 1.0]), np.pi / 2) @ [1, 0, 0], 6).tolist()
        [0.0, 1.0, 0.0]
    """
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def joint_motion(joint: Joint, q: float) -> np.ndarray:
    """(4, 4) motion of ``joint`` at value ``q`` in its own frame (identity for fixed and floating joints)."""
    m = np.eye(4)
    if joint.type in ("revolute", "continuous"):
        m[:3, :3] = axis_angle_matrix(joint.axis, q)
    elif joint.type == "prismatic":
        m[:3, 3] = joint.axis * q
    return m


def joint_limits(joint: Joint) -> tuple[float, float]:
    """(lower, upper) of a moving joint: continuous joints span [0, 2 pi]; joints without limits [0, 0]."""
    if joint.type == "continuous":
        return 0.0, 2.0 * np.pi
    return joint.lower, joint.upper


def joint_values(urdf: Urdf, mode: str, rng: np.random.Generator | None = None) -> dict[str, float]:
    """The value of every moving joint for a state mode.

    Args:
        urdf: the parsed file.
        mode: ``rest`` (0 clamped into [lower, upper]; continuous joints 0) or ``random`` (uniform in
            [lower, upper]; continuous joints uniform in [0, 2 pi)), drawn in file order.
        rng: the generator ``random`` draws from.

    Returns:
        ``{joint name: value}`` for revolute, prismatic and continuous joints (radians or metres).

    Raises:
        AffnerfError: an unknown mode.
        ValueError: ``random`` without ``rng``.

    Example:
        >>> from pathlib import Path
        >>> from affnerf.data.partnet.urdf import Joint
        >>> j = Joint("lid", "prismatic", "body", "lid", np.eye(4), np.array([0, 1.0, 0]), -0.108, -0.008, True)
        >>> joint_values(Urdf(Path("m.urdf"), "", {}, (j,)), "rest")
        {'lid': -0.008}
    """
    if mode not in JOINT_STATE_MODES:
        raise AffnerfError(f"unknown joint state mode {mode!r} (known: {', '.join(JOINT_STATE_MODES)})")
    if mode == "random" and rng is None:
        raise ValueError("joint state mode 'random' needs an rng")
    values: dict[str, float] = {}
    for joint in urdf.joints:
        if joint.type not in MOVING_TYPES:
            continue
        if mode == "rest":
            lower, upper = (0.0, 0.0) if joint.type == "continuous" else (joint.lower, joint.upper)
            values[joint.name] = float(np.clip(0.0, lower, upper))
        elif joint.type == "continuous":
            assert rng is not None
            values[joint.name] = float(rng.uniform(0.0, 2.0 * np.pi))
        else:
            assert rng is not None
            values[joint.name] = float(rng.uniform(joint.lower, joint.upper))
    return values


def link_poses(urdf: Urdf, values: dict[str, float]) -> dict[str, np.ndarray]:
    """World (4, 4) pose of every link for the given joint values.

    Args:
        urdf: the parsed file (each link has at most one parent joint; see :func:`parse_urdf`).
        values: joint values by name; moving joints not named are at 0.

    Returns:
        ``{link name: (4, 4) pose}`` for every link.

    Raises:
        AffnerfError: when the joints form a cycle (naming the URDF file).
    """
    parent_joint = {j.child: j for j in urdf.joints}
    poses: dict[str, np.ndarray] = {}

    def pose(link: str, trail: tuple[str, ...]) -> np.ndarray:
        if link in poses:
            return poses[link]
        if link in trail:
            raise input_error(urdf.path, f"joints form a cycle through link {link!r}")
        joint = parent_joint.get(link)
        if joint is None:
            result = np.eye(4)
        else:
            motion = joint_motion(joint, values.get(joint.name, 0.0))
            result = pose(joint.parent, (*trail, link)) @ joint.origin @ motion
        poses[link] = result
        return result

    for name in urdf.links:
        pose(name, ())
    return poses


def descendant_links(urdf: Urdf, link: str) -> set[str]:
    """``link`` and every link below it in the joint tree."""
    children: dict[str, list[str]] = {}
    for joint in urdf.joints:
        children.setdefault(joint.parent, []).append(joint.child)
    out, stack = set(), [link]
    while stack:
        name = stack.pop()
        if name not in out:
            out.add(name)
            stack.extend(children.get(name, []))
    return out
