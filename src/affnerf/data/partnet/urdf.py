"""A small URDF reader: links with their mesh visuals and joints, as typed dataclasses (``xml.etree``).

Only what object import needs is read: visual meshes (filename, origin, scale), and joints (type, parent, child,
origin, axis, limits). Numbers are read leniently because real PartNet-Mobility files hold a few typos (e.g. a
limit written ``-z0.008``): a token that still holds one number keeps it, with a warning naming the file and the
attribute; a token that holds none is an :class:`~affnerf.errors.AffnerfError`.
"""

from __future__ import annotations

import logging
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, cast

import numpy as np

from affnerf.errors import input_error

logger = logging.getLogger(__name__)

JointType = Literal["fixed", "revolute", "prismatic", "continuous", "floating"]
JOINT_TYPES: tuple[str, ...] = ("fixed", "revolute", "prismatic", "continuous", "floating")

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


@dataclass(frozen=True)
class Visual:
    """One mesh visual of a link.

    Attributes:
        filename: the mesh file as written in the URDF (relative to the URDF's folder).
        origin: (4, 4) pose of the mesh in the link frame.
        scale: (3,) per-axis scale applied to the mesh before ``origin``.
        name: the visual's ``name`` attribute (PartNet-Mobility writes ``<leaf name>-<leaf id>``), or ``""``.
    """

    filename: str
    origin: np.ndarray
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    name: str = ""


@dataclass(frozen=True)
class Link:
    """A rigid body: a name and its mesh visuals."""

    name: str
    visuals: tuple[Visual, ...] = ()


@dataclass(frozen=True)
class Joint:
    """A joint between two links; URDF semantics: child frame = parent frame · origin · motion(q).

    Attributes:
        name: joint name.
        type: ``fixed``, ``revolute``, ``prismatic``, ``continuous`` or ``floating`` (kept rigid on import).
        parent: parent link name.
        child: child link name.
        origin: (4, 4) pose of the joint frame in the parent link frame.
        axis: (3,) unit axis in the joint frame (rotation axis or sliding direction).
        lower: lower limit (radians or metres); 0 where the file gives none.
        upper: upper limit; 0 where the file gives none.
        has_limits: whether the file gave a ``<limit>`` with bounds.
    """

    name: str
    type: JointType
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float = 0.0
    upper: float = 0.0
    has_limits: bool = False


@dataclass(frozen=True)
class Urdf:
    """A parsed URDF.

    Attributes:
        path: the file it was read from.
        name: the robot name.
        links: links by name, in file order.
        joints: joints in file order.
    """

    path: Path
    name: str
    links: dict[str, Link]
    joints: tuple[Joint, ...]


def parse_number(text: str, path: Path, what: str) -> float:
    """Read one number, salvaging typos that still hold exactly one number.

    Args:
        text: the token, e.g. ``"0.5"`` or ``"-z0.008"``.
        path: the file, for messages.
        what: the element and attribute, for messages (e.g. ``joint 'joint_2' limit lower``).

    Returns:
        The value; a salvaged one keeps a leading ``-`` of the token (``"-z0.008"`` gives -0.008).

    Raises:
        AffnerfError: when the token holds no number, or several, or a non-finite one.

    Example:
        >>> parse_number("-z0.008", Path("mobility.urdf"), "limit lower")
        -0.008
    """
    token = text.strip()
    try:
        value = float(token)
    except ValueError:
        found = _NUMBER.findall(token)
        if len(found) != 1:
            raise input_error(path, f"{what}: cannot read a number from {text!r}") from None
        value = float(found[0])
        if token.startswith("-") and not found[0].startswith(("-", "+")):
            value = -value
        logger.warning("%s: %s: malformed number %r read as %r", path, what, text, value)
    if not np.isfinite(value):
        raise input_error(path, f"{what}: non-finite number {text!r}")
    return value


def parse_vector(text: str | None, path: Path, what: str, size: int, default: tuple[float, ...]) -> np.ndarray:
    """Read a whitespace-separated vector of ``size`` numbers, or ``default`` when ``text`` is ``None``.

    Returns:
        (size,) float64 array.

    Raises:
        AffnerfError: on a wrong count or an unreadable number.
    """
    if text is None:
        return np.asarray(default, np.float64)
    tokens = text.split()
    if len(tokens) != size:
        raise input_error(path, f"{what}: expected {size} numbers, got {text!r}")
    return np.array([parse_number(t, path, what) for t in tokens], np.float64)


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """(3, 3) rotation of URDF roll-pitch-yaw (fixed axes X, then Y, then Z): ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``.

    Example:
        >>> np.round(rpy_matrix(np.array([np.pi / 2, 0, 0])) @ [0, 1, 0], 6).tolist()  # y-up onto z-up
        [0.0, 0.0, 1.0]
    """
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def origin_matrix(xyz: np.ndarray, rpy: np.ndarray) -> np.ndarray:
    """(4, 4) pose from a URDF ``<origin xyz rpy>``: rotation ``rpy_matrix(rpy)``, translation ``xyz``."""
    m = np.eye(4)
    m[:3, :3] = rpy_matrix(rpy)
    m[:3, 3] = xyz
    return m


def _origin(elem: ET.Element | None, path: Path, what: str) -> np.ndarray:
    """(4, 4) pose of an optional ``<origin>`` element (identity when absent)."""
    if elem is None:
        return np.eye(4)
    xyz = parse_vector(elem.get("xyz"), path, f"{what} origin xyz", 3, (0.0, 0.0, 0.0))
    rpy = parse_vector(elem.get("rpy"), path, f"{what} origin rpy", 3, (0.0, 0.0, 0.0))
    return origin_matrix(xyz, rpy)


def _parse_link(elem: ET.Element, path: Path) -> Link:
    name = _required(elem, "name", path, "link")
    visuals = []
    for vis in elem.findall("visual"):
        what = f"link {name!r} visual"
        mesh = vis.find("geometry/mesh")
        if mesh is None or not mesh.get("filename"):
            logger.warning("%s: %s has no mesh geometry; skipped", path, what)
            continue
        scale = parse_vector(mesh.get("scale"), path, f"{what} mesh scale", 3, (1.0, 1.0, 1.0))
        visuals.append(
            Visual(
                filename=str(mesh.get("filename")),
                origin=_origin(vis.find("origin"), path, what),
                scale=(float(scale[0]), float(scale[1]), float(scale[2])),
                name=vis.get("name", ""),
            )
        )
    return Link(name=name, visuals=tuple(visuals))


def _required(elem: ET.Element, attr: str, path: Path, what: str) -> str:
    value = elem.get(attr)
    if not value:
        raise input_error(path, f"{what} without a {attr!r} attribute")
    return value


def _parse_joint(elem: ET.Element, path: Path) -> Joint:
    name = _required(elem, "name", path, "joint")
    what = f"joint {name!r}"
    jtype = elem.get("type", "")
    if jtype not in JOINT_TYPES:
        raise input_error(path, f"{what}: unsupported joint type {jtype!r} (known: {', '.join(JOINT_TYPES)})")
    parent, child = elem.find("parent"), elem.find("child")
    if parent is None or child is None:
        raise input_error(path, f"{what}: needs a parent and a child")
    axis = parse_vector(_attr(elem.find("axis"), "xyz"), path, f"{what} axis xyz", 3, (1.0, 0.0, 0.0))
    norm = float(np.linalg.norm(axis))
    if norm < 1e-12 and jtype in ("revolute", "prismatic", "continuous"):
        raise input_error(path, f"{what}: zero axis")
    limit = elem.find("limit")
    has_limits = limit is not None and limit.get("lower") is not None and limit.get("upper") is not None
    lower = upper = 0.0
    if has_limits:
        assert limit is not None
        lower = parse_number(str(limit.get("lower")), path, f"{what} limit lower")
        upper = parse_number(str(limit.get("upper")), path, f"{what} limit upper")
        if lower > upper:
            logger.warning("%s: %s: limit lower %r > upper %r; swapped", path, what, lower, upper)
            lower, upper = upper, lower
    elif jtype in ("revolute", "prismatic"):
        logger.warning("%s: %s: %s joint without limits; held at 0", path, what, jtype)
    return Joint(
        name=name,
        type=cast(JointType, jtype),
        parent=_required(parent, "link", path, f"{what} parent"),
        child=_required(child, "link", path, f"{what} child"),
        origin=_origin(elem.find("origin"), path, what),
        axis=axis / norm if norm >= 1e-12 else axis,
        lower=lower,
        upper=upper,
        has_limits=has_limits,
    )


def _attr(elem: ET.Element | None, attr: str) -> str | None:
    return None if elem is None else elem.get(attr)


def parse_urdf(path: Path) -> Urdf:
    """Read a URDF file.

    Args:
        path: the ``.urdf`` file.

    Returns:
        Its links (with mesh visuals) and joints. Every joint's parent and child name a link, and each link has
        at most one parent joint.

    Raises:
        AffnerfError: a missing or unparseable file, an unreadable number, an unknown joint type, a joint naming
        an unknown link, or a link with two parents.
    """
    path = Path(path)
    if not path.is_file():
        raise input_error(path, "file not found")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise input_error(path, f"not a valid XML file ({exc})") from None
    if root.tag != "robot":
        raise input_error(path, f"not a URDF file (root element <{root.tag}>, expected <robot>)")
    links: dict[str, Link] = {}
    for elem in root.findall("link"):
        link = _parse_link(elem, path)
        if link.name in links:
            raise input_error(path, f"link {link.name!r} is defined twice")
        links[link.name] = link
    joints = tuple(_parse_joint(elem, path) for elem in root.findall("joint"))
    children: set[str] = set()
    for joint in joints:
        for end in (joint.parent, joint.child):
            if end not in links:
                raise input_error(path, f"joint {joint.name!r} names unknown link {end!r}")
        if joint.child in children:
            raise input_error(path, f"link {joint.child!r} is the child of more than one joint")
        children.add(joint.child)
    return Urdf(path=path, name=root.get("name", ""), links=links, joints=joints)
