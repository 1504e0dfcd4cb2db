"""Cabinets: a hollow carcass with shelves (support), doors and drawers (open) with handles (pull); articulated.

Orientation: the cabinet stands on the floor (z = 0) with +z up; its front, where the doors and drawers are, faces
-y; x runs from its left to its right side (seen from the front, left is -x).

Shape parameters (metres): width, height (of the carcass), depth, board thickness, front thickness, gap between
fronts, base height and inset, top overhang, drawer height, handle length, radius and standoff, handle height on
a door. Styles: 0 (a chest of drawers), 1 or 2 doors; 0..3 drawers above the doors; hinge side of a single door;
``plinth`` or ``legs`` base; ``bar`` or ``knob`` handles; ``flat`` or ``framed`` (shaker) fronts; 0..2 shelves.

Joints (``ObjectAsset.joints``), each moving its front, its handle and (drawers) its box:
- doors ``door`` (one door) or ``door_left`` / ``door_right``: revolute about the vertical axis through the hinged
  edge of the door's back face (x at the door's outer edge, y = -depth / 2); value 0 = closed, up to
  :data:`DOOR_LIMIT` radians, opening outward (a left-hinged door turns by -value about +z, a right-hinged one by
  +value);
- drawers ``drawer_0`` (top) ..: prismatic along -y, value 0 = closed, up to 0.8 x depth metres.
The states are drawn at random (closed with probability 0.4, else uniform within the limits) and stored in the
params; :func:`build` takes explicit states to override them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import trimesh

from affnerf.errors import AffnerfError
from affnerf.objects.appearance import metal, random_color, shade
from affnerf.objects.asset import JointState, Material, ObjectAsset, Part
from affnerf.objects.categories import _cabinet_parts as cp
from affnerf.objects.primitives import placed, translation

#: Upper limit of a door's opening angle (radians).
DOOR_LIMIT = 1.9
#: Upper limit of a drawer's travel, as a fraction of the cabinet's depth.
DRAWER_TRAVEL = 0.8
#: Chance that a joint is sampled closed.
P_CLOSED = 0.4


@dataclass(frozen=True)
class CabinetParams:
    """Shape, style and joint-state parameters of a cabinet (metres, radians)."""

    width: float  # outer width of the carcass (x)
    height: float  # height of the carcass below the top slab (z)
    depth: float  # outer depth of the carcass (y)
    thickness: float  # board thickness of the carcass and shelves
    front_thickness: float  # thickness of doors and drawer fronts
    gap: float  # gap between neighbouring fronts
    base_height: float  # height of the plinth or legs
    base_inset: float  # how far the plinth or legs are set back from the carcass's edges
    top_overhang: float  # how far the top slab reaches past the sides and front
    drawer_height: float  # height of one drawer (at most half the carcass shared by all drawers, with doors)
    handle_length: float  # bar length (knob diameter is a fifth of it)
    handle_radius: float  # bar radius
    handle_standoff: float  # distance from the front to the bar's axis
    handle_height: float  # a door handle's height as a fraction of the door's height
    n_doors: int  # 0 (chest of drawers), 1 or 2
    n_drawers: int  # 0..3, stacked at the top
    n_shelves: int  # 0..2 shelves behind the doors
    hinge: Literal["left", "right"]  # hinge side of a single door
    base: Literal["plinth", "legs"]
    handle: Literal["bar", "knob"]
    front: Literal["flat", "framed"]
    door_angles: tuple[float, ...]  # opening angle of each door, in door order
    drawer_openings: tuple[float, ...]  # how far each drawer is pulled out, top first


def _joint_value(rng: np.random.Generator, upper: float) -> float:
    """Closed with probability :data:`P_CLOSED`, otherwise uniform in [0, upper]."""
    return 0.0 if rng.uniform() < P_CLOSED else float(rng.uniform(0.0, upper))


def sample_params(rng: np.random.Generator) -> CabinetParams:
    """Draw cabinet parameters and joint states."""
    width, height, depth = rng.uniform(0.4, 1.0), rng.uniform(0.45, 1.5), rng.uniform(0.3, 0.6)
    n_drawers = int(rng.integers(0, 4))
    if n_drawers >= 2 and rng.uniform() < 0.3:
        n_doors = 0
        height = n_drawers * rng.uniform(0.16, 0.32)  # a chest's drawers keep a drawer's height
    else:
        n_doors = 2 if rng.uniform() < min(0.9, width) else 1
    base = ("plinth", "legs")[rng.integers(2)]
    return CabinetParams(
        width=width,
        height=height,
        depth=depth,
        thickness=rng.uniform(0.014, 0.026),
        front_thickness=rng.uniform(0.016, 0.026),
        gap=rng.uniform(0.002, 0.006),
        base_height=rng.uniform(0.03, 0.1) if base == "plinth" else rng.uniform(0.08, 0.22),
        base_inset=rng.uniform(0.0, 0.05),
        top_overhang=0.0 if rng.uniform() < 0.4 else rng.uniform(0.005, 0.03),
        drawer_height=rng.uniform(0.1, 0.22),
        handle_length=rng.uniform(0.08, 0.22),
        handle_radius=rng.uniform(0.004, 0.008),
        handle_standoff=rng.uniform(0.02, 0.035),
        handle_height=rng.uniform(0.45, 0.85),
        n_doors=n_doors,
        n_drawers=n_drawers,
        n_shelves=int(rng.integers(0, 3)) if n_doors else 0,
        hinge=("left", "right")[rng.integers(2)],
        base=base,
        handle=("bar", "knob")[rng.integers(2)],
        front=("flat", "framed")[rng.integers(2)],
        door_angles=tuple(_joint_value(rng, DOOR_LIMIT) for _ in range(n_doors)),
        drawer_openings=tuple(_joint_value(rng, DRAWER_TRAVEL * depth) for _ in range(n_drawers)),
    )


def band_edges(p: CabinetParams) -> np.ndarray:
    """(n_bands + 1,) heights splitting the carcass's front into bands, bottom first.

    The top ``n_drawers`` bands hold drawers; with doors, the bottom band holds them. Inner edges are the
    centres of the carcass's dividers.
    """
    z0, z1 = p.base_height, p.base_height + p.height
    if p.n_doors == 0:
        return np.linspace(z0, z1, p.n_drawers + 1)
    drawer = min(p.drawer_height, 0.5 * p.height / max(p.n_drawers, 1))
    tops = [z1 - k * drawer for k in range(p.n_drawers, 0, -1)]
    return np.array([z0] + tops + [z1])


def _band_interior(p: CabinetParams, edges: np.ndarray, i: int) -> tuple[float, float]:
    """Floor and ceiling of band ``i``'s compartment (inside the bottom board, dividers and top slab)."""
    floor = edges[i] + (p.thickness if i == 0 else p.thickness / 2)
    ceiling = edges[i + 1] - (0.0 if i == len(edges) - 2 else p.thickness / 2)
    return float(floor), float(ceiling)


def door_names(p: CabinetParams) -> list[str]:
    """Names of the doors (and of their joints), in the order of ``door_angles``."""
    return {0: [], 1: ["door"], 2: ["door_left", "door_right"]}[p.n_doors]


def joint_values(p: CabinetParams) -> dict[str, float]:
    """The sampled joint states by joint name."""
    values = dict(zip(door_names(p), p.door_angles, strict=True))
    values.update({f"drawer_{i}": v for i, v in enumerate(p.drawer_openings)})
    return values


def _front_box(p: CabinetParams, x0: float, x1: float, z0: float, z1: float) -> tuple[np.ndarray, np.ndarray]:
    """Corners (lo, hi) of a front covering x0..x1, z0..z1 less half a gap on each side."""
    g, y = p.gap / 2, -p.depth / 2
    return np.array([x0 + g, y - p.front_thickness, z0 + g]), np.array([x1 - g, y, z1 - g])


def _handle_mesh(p: CabinetParams, vertical: bool, span: float, at: np.ndarray) -> trimesh.Trimesh:
    """A bar or knob(s) on a front face at point ``at`` (3,); ``span`` is the front's size along the bar."""
    if p.handle == "knob":
        k = cp.knob(0.1 * p.handle_length + 0.008, p.handle_standoff)
        offsets = [0.0] if vertical or span < 0.5 else [-span / 4, span / 4]
        return cp.join([placed(k, translation(at + [dx, 0.0, 0.0])) for dx in offsets])
    length = min(p.handle_length, 0.5 * span)
    return placed(cp.bar_handle(length, p.handle_radius, p.handle_standoff, vertical), translation(at))


def _door_parts(
    p: CabinetParams, angles: Mapping[str, float], front: Material, metal_: Material
) -> tuple[list[Part], list[JointState]]:
    """Parts and joints of the doors, each door and its handle turned about its hinge."""
    edges = band_edges(p)
    w = p.width / 2
    spans = {"door": (-w, w), "door_left": (-w, 0.0), "door_right": (0.0, w)}
    parts, joints = [], []
    for name in door_names(p):
        lo, hi = _front_box(p, *spans[name], edges[0], edges[1])
        side = {"door": p.hinge, "door_left": "left", "door_right": "right"}[name]
        inset = 0.035 + (p.handle_radius if p.handle == "bar" else 0.0)
        x = hi[0] - inset if side == "left" else lo[0] + inset
        z = lo[2] + p.handle_height * (hi[2] - lo[2])
        z = float(np.clip(z, lo[2] + 0.3 * (hi[2] - lo[2]), hi[2] - 0.25 * min(p.handle_length, 0.5 * (hi[2] - lo[2]))))
        handle = _handle_mesh(p, True, hi[2] - lo[2], np.array([x, lo[1], z]))
        hinge = (lo[0], hi[1]) if side == "left" else (hi[0], hi[1])
        angle = angles[name]
        move = cp.hinge_transform(hinge, -angle if side == "left" else angle)
        parts += [
            Part(name, "open", placed(cp.front_panel(lo, hi, p.front == "framed"), move), materials=(front,)),
            Part(f"handle_{name}", "pull", placed(handle, move), materials=(metal_,)),
        ]
        joints.append(JointState(name, "revolute", angle, 0.0, DOOR_LIMIT, (name, f"handle_{name}")))
    return parts, joints


def _drawer_parts(
    p: CabinetParams, openings: Mapping[str, float], front: Material, inner: Material, metal_: Material
) -> tuple[list[Part], list[JointState]]:
    """Parts and joints of the drawers (top first), each front, box and handle slid out along -y."""
    edges = band_edges(p)
    w, t, c = p.width / 2, p.thickness, 0.004
    parts, joints = [], []
    for i in range(p.n_drawers):
        band = len(edges) - 2 - i
        lo, hi = _front_box(p, -w, w, edges[band], edges[band + 1])
        floor, ceiling = _band_interior(p, edges, band)
        box_lo = np.array([-w + t + c, -p.depth / 2, floor + c])
        box_hi = np.array([w - t - c, -p.depth / 2 + 0.9 * (p.depth - t), floor + 0.8 * (ceiling - floor)])
        handle = _handle_mesh(p, False, hi[0] - lo[0], np.array([0.0, lo[1], 0.5 * (lo[2] + hi[2])]))
        name = f"drawer_{i}"
        move = cp.slide_transform(openings[name])
        names = (f"{name}_front", f"{name}_box", f"handle_{name}")
        parts += [
            Part(names[0], "open", placed(cp.front_panel(lo, hi, p.front == "framed"), move), materials=(front,)),
            Part(names[1], "open", placed(cp.drawer_box(box_lo, box_hi, 0.6 * t), move), materials=(inner,)),
            Part(names[2], "pull", placed(handle, move), materials=(metal_,)),
        ]
        upper = DRAWER_TRAVEL * p.depth
        joints.append(JointState(name, "prismatic", openings[name], 0.0, upper, names))
    return parts, joints


def _fixed_parts(p: CabinetParams, body: Material, inner: Material) -> list[Part]:
    """The frame (carcass), the base and the shelves."""
    edges = band_edges(p)
    frame = cp.carcass(p.width, p.depth, p.height, p.thickness, p.base_height, p.top_overhang, list(edges[1:-1]))
    if p.base == "plinth":
        base = cp.plinth(p.width, p.depth, p.base_height + 0.002, p.base_inset)
    else:
        base = cp.legs(p.width, p.depth, p.base_height + 0.002, p.base_inset, 0.012 + 0.02 * p.thickness / 0.026)
    parts = [Part("frame", "support", frame, materials=(body,)), Part("base", "support", base, materials=(body,))]
    floor, ceiling = _band_interior(p, edges, 0)
    w, d, t = p.width / 2, p.depth / 2, p.thickness
    for k in range(p.n_shelves if p.n_doors else 0):
        z = floor + (k + 1) * (ceiling - floor) / (p.n_shelves + 1)
        shelf = cp.board((-w + t, -d + 0.02, z - t / 2), (w - t, d - t, z + t / 2))
        parts.append(Part(f"shelf_{k}", "support", shelf, materials=(inner,)))
    return parts


def build(
    p: CabinetParams,
    body: Material,
    front: Material,
    handle: Material,
    joints: Mapping[str, float] | None = None,
) -> ObjectAsset:
    """Build the cabinet's parts in the given joint states.

    Args:
        p: the parameters.
        body: the carcass's and base's material (shelves and drawer boxes use a lighter shade of it).
        front: the doors' and drawer fronts' material.
        handle: the handles' material.
        joints: joint name -> state, overriding the states in ``p`` (e.g. all 0.0 for a closed cabinet).

    Raises:
        AffnerfError: for an unknown joint name or a state outside the joint's limits.
    """
    values = joint_values(p)
    for name, value in (joints or {}).items():
        if name not in values:
            raise AffnerfError(f"cabinet has no joint {name!r} (joints: {', '.join(values) or 'none'})")
        values[name] = float(value)
    inner = Material(color=shade(body.color, 1.15))
    door_parts, door_joints = _door_parts(p, values, front, handle)
    drawer_parts, drawer_joints = _drawer_parts(p, values, front, inner, handle)
    for j in door_joints + drawer_joints:
        if not j.lower <= j.value <= j.upper:
            raise AffnerfError(f"joint {j.name!r} state {j.value} outside [{j.lower}, {j.upper}]")
    parts = _fixed_parts(p, body, inner) + door_parts + drawer_parts
    return ObjectAsset(category="cabinet", parts=parts, params=asdict(p), joints=door_joints + drawer_joints)


def _wood(rng: np.random.Generator) -> Material:
    """A wood tone, sometimes with a faint grain (stripes across x), or a painted colour."""
    if rng.uniform() < 0.4:
        return Material(color=random_color(rng, saturation=(0.05, 0.5), value=(0.5, 0.95)))
    color = random_color(rng, hue=(0.05, 0.12), saturation=(0.3, 0.75), value=(0.3, 0.85))
    if rng.uniform() < 0.5:
        return Material(color=color)
    axis = np.array([1.0, 0.0, rng.uniform(-0.15, 0.15)])
    axis /= np.linalg.norm(axis)
    return Material(
        color=color,
        pattern="stripes",
        color2=shade(color, rng.uniform(0.8, 0.92)),
        period=float(rng.uniform(0.004, 0.012)),
        axis=(float(axis[0]), float(axis[1]), float(axis[2])),
    )


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random cabinet in a random joint state."""
    params = sample_params(rng)
    body = _wood(rng)
    front = body if rng.uniform() < 0.6 else _wood(rng)
    handle = metal(rng) if rng.uniform() < 0.6 else Material(color=random_color(rng, value=(0.05, 0.35)))
    return build(params, body, front, handle)
