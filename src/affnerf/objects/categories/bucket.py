"""Buckets: a hollow body with a rolled lip and two ears (contain) and a wire bail handle (grasp), with an
optional grip sleeve on the bail (grasp).

Canonical orientation: the bucket stands on its base with its axis along +z and its opening up; the bail's pivots
(the ears) sit on the +x and -x sides, so an upright bail spans the xz plane; a dropped bail leans toward +y or -y.

Shape parameters: height, top radius, bottom/top radius ratio (taper), wall thickness, lip size, wall bulge
(profile curve), squareness and aspect of a square-ish body, bail arc height, bail squareness, wire radius,
handle tilt (share of the way from upright to resting on the body), grip length. Styles: round or square-ish
body; with or without a grip sleeve; with or without stacking ribs on the wall.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import trimesh

from affnerf.objects.appearance import metal, random_color, random_material
from affnerf.objects.asset import Material, ObjectAsset, Part
from affnerf.objects.primitives import placed, revolve, rotation, translation, tube

#: Rotation taking a part built along +z onto +x (for the ears).
_Z_TO_X = rotation((0.0, 1.0, 0.0), np.pi / 2)


@dataclass(frozen=True)
class BucketParams:
    """Shape parameters of a bucket (metres, radians)."""

    height: float
    top_radius: float  # outer radius of the wall just below the lip (half-width for a square-ish body)
    bottom_ratio: float  # bottom radius over top radius
    wall: float  # wall and floor thickness
    lip: float  # how far the rolled lip stands out of the wall
    bulge: float  # outward bow of the wall's middle, relative to the top radius
    squareness: float  # superellipse exponent of the body's cross-section: 2 = round
    aspect: float  # depth (y) over width (x) of the cross-section
    arc_height: float  # height of the bail's arc above its pivots, relative to the pivots' half-distance
    bail_squareness: float  # superellipse exponent of the bail's arc: 2 = elliptic, larger = flatter top
    wire_radius: float
    handle_tilt: float  # -1..1: share of the way from upright (0) to resting on the body, sign = side
    grip_length: float  # length of the grip sleeve (0 without one)
    shape: Literal["round", "square"]
    grip: bool
    ribs: bool


def sample_params(rng: np.random.Generator) -> BucketParams:
    """Draw bucket parameters."""
    shape = ("round", "square")[rng.choice(2, p=(0.65, 0.35))]
    grip = bool(rng.uniform() < 0.5)
    height = rng.uniform(0.16, 0.38)
    tilted = rng.uniform() < 0.6
    return BucketParams(
        height=height,
        top_radius=rng.uniform(0.36, 0.7) * height,
        bottom_ratio=rng.uniform(0.68, 1.0),
        wall=rng.uniform(0.0018, 0.005),
        lip=rng.uniform(0.003, 0.011),
        bulge=rng.uniform(-0.01, 0.05) if rng.uniform() < 0.4 else 0.0,
        squareness=rng.uniform(3.0, 5.5) if shape == "square" else 2.0,
        aspect=rng.uniform(0.72, 1.0) if shape == "square" else 1.0,
        arc_height=rng.uniform(0.55, 1.15),
        bail_squareness=rng.uniform(2.0, 3.5),
        wire_radius=rng.uniform(0.0022, 0.0045),
        handle_tilt=float(rng.choice((-1.0, 1.0))) * rng.uniform(0.3, 1.0) if tilted else 0.0,
        grip_length=rng.uniform(0.08, 0.13) if grip else 0.0,
        shape=shape,
        grip=grip,
        ribs=bool(rng.uniform() < 0.4),
    )


def _outer_radius(p: BucketParams, z: np.ndarray) -> np.ndarray:
    """(N,) radius of the wall's outer surface at heights z (N,), without ribs or lip."""
    r_top, r_bottom = p.top_radius, p.top_radius * p.bottom_ratio
    u = np.clip(z / p.height, 0.0, 1.0)
    return r_bottom + (r_top - r_bottom) * u + p.bulge * p.top_radius * np.sin(np.pi * u)


def _lip_height(p: BucketParams) -> float:
    """Height of the rolled lip."""
    return 2.2 * p.lip + 0.004


def _outer_profile(p: BucketParams, n: int = 160) -> np.ndarray:
    """(K, 2) (radius, z) outline of the outside from the base's edge up over the lip to the rim's top."""
    h, lh, lip, r_top = p.height, _lip_height(p), p.lip, p.top_radius
    chamfer = min(0.006, 0.05 * h)
    z = np.linspace(chamfer, h - lh, n)
    r = _outer_radius(p, z)
    if p.ribs:
        for z_rib in (h - lh - 0.012, h - lh - 0.026, 0.1 * h):
            r = r + 0.5 * lip * np.exp(-0.5 * ((z - z_rib) / 0.0025) ** 2)
    base = np.array([[_outer_radius(p, np.zeros(1))[0] - chamfer, 0.0]])
    bead = np.array(
        [
            [r_top + 0.6 * lip, h - 0.9 * lh],
            [r_top + lip, h - 0.6 * lh],
            [r_top + lip, h - 0.3 * lh],
            [r_top + 0.6 * lip, h],
        ]
    )
    return np.vstack([base, np.stack([r, z], 1), bead])


def _body_profile(p: BucketParams, n: int = 60) -> np.ndarray:
    """(K, 2) (radius, z) outline of the whole body: outside, over the rim, down the inside to the inner floor."""
    z = np.linspace(p.height, 1.5 * p.wall, n)
    inner = np.stack([_outer_radius(p, z) - p.wall, z], 1)
    return np.vstack([_outer_profile(p), inner])


def _squarify(mesh: trimesh.Trimesh, p: BucketParams) -> trimesh.Trimesh:
    """Map each circle about the z axis onto a superellipse of the same half-width (a no-op for a round body)."""
    if p.shape == "round":
        return mesh
    v = mesh.vertices.copy()
    rho = np.hypot(v[:, 0], v[:, 1])
    theta = np.arctan2(v[:, 1], v[:, 0])
    c, s = np.cos(theta), np.sin(theta)
    k = 2.0 / p.squareness
    v[:, 0] = rho * np.sign(c) * np.abs(c) ** k
    v[:, 1] = rho * p.aspect * np.sign(s) * np.abs(s) ** k
    return trimesh.Trimesh(v, mesh.faces.copy(), process=False)


def _ear_height(p: BucketParams) -> float:
    """Height of the bail's pivot axis."""
    return p.height - _lip_height(p) - 0.012 - 2.0 * p.wire_radius


def _pivot_x(p: BucketParams) -> float:
    """Distance of each pivot from the axis: clear of the lip by a little more than the wire."""
    return p.top_radius + p.lip + 2.0 * p.wire_radius + 0.005


def _ears(p: BucketParams) -> list[trimesh.Trimesh]:
    """The two ears: rounded bosses on the wall at +-x holding the bail's ends.

    A boss's inner end follows the sloping wall, half-way into it, so it neither pokes through to the inside
    nor leaves a gap.
    """
    z = _ear_height(p)
    x0 = float(_outer_radius(p, np.array([z]))[0])
    radius = 2.2 * p.wire_radius + 0.004
    length = _pivot_x(p) + 1.5 * p.wire_radius - x0
    boss = revolve(np.array([[radius, 0.0], [radius, length - 0.002], [radius - 0.002, length]]), segments=24)
    inner_end = boss.vertices[:, 2] < 1e-9
    right = placed(boss, _Z_TO_X, translation((x0, 0.0, z)))
    vertices = right.vertices.copy()
    vertices[inner_end, 0] = _outer_radius(p, vertices[inner_end, 2]) - 0.5 * p.wall
    right = trimesh.Trimesh(vertices, right.faces.copy(), process=False)
    return [right, placed(right, rotation((0.0, 0.0, 1.0), np.pi))]


def _arc(p: BucketParams, n: int = 120) -> np.ndarray:
    """(n, 2) (x, z) half-superellipse of the bail above its pivot axis (z = 0), from +x over the top to -x."""
    x_p = _pivot_x(p)
    h = p.arc_height * x_p
    t = np.linspace(0.0, np.pi, n)
    k = 2.0 / p.bail_squareness
    c, s = np.cos(t), np.sin(t)
    return np.stack([x_p * np.sign(c) * np.abs(c) ** k, h * np.abs(s) ** k], 1)


def _bail_path(p: BucketParams) -> np.ndarray:
    """(N, 3) centre line of the bail in the pivot frame: hooks into both ears, filleted into the arc."""
    x_p, fillet = _pivot_x(p), 2.0 * p.wire_radius
    hook = 0.006
    phi = np.linspace(-0.5 * np.pi, 0.0, 6)[1:-1]
    corner = np.stack([x_p - fillet + fillet * np.cos(phi), fillet + fillet * np.sin(phi)], 1)
    arc = _arc(p) + np.array([0.0, fillet])
    start = np.array([[x_p - fillet - hook, 0.0], [x_p - fillet, 0.0]])
    right = np.vstack([start, corner])
    xz = np.vstack([right, arc, (right * np.array([-1.0, 1.0]))[::-1]])
    return np.stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]], 1)


def _grip_path(p: BucketParams) -> np.ndarray:
    """(M, 3) the middle stretch of the arc, ``grip_length`` long, that the sleeve covers (pivot frame)."""
    arc = _arc(p, 400) + np.array([0.0, 2.0 * p.wire_radius])
    seg = np.linalg.norm(np.diff(arc, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    half_length = 0.5 * min(p.grip_length, 0.5 * s[-1])
    keep = np.abs(s - 0.5 * s[-1]) <= half_length
    xz = arc[keep][:: max(1, int(keep.sum()) // 40)]
    return np.stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]], 1)


def _grip_radius(p: BucketParams) -> float:
    """Radius of the grip sleeve."""
    return 2.6 * p.wire_radius + 0.004


def _touches_body(p: BucketParams, points: np.ndarray, clearance: float) -> bool:
    """Whether any of (N, 3) points (canonical frame) comes within ``clearance`` of the body's outside."""
    outer = _outer_profile(p)
    z = points[:, 2]
    level = (z > -clearance) & (z < p.height + clearance)
    radius = np.interp(z, outer[:, 1], outer[:, 0]) + clearance
    e = p.squareness
    norm = np.abs(points[:, 0] / radius) ** e + np.abs(points[:, 1] / (p.aspect * radius)) ** e
    return bool(np.any(level & (norm < 1.0)))


def _tilt_angle(p: BucketParams) -> float:
    """The bail's turn about its pivot axis: ``handle_tilt`` of the largest turn before it meets the body or the
    ground (a bail let go falls until it rests on the rim or hangs against the wall)."""
    z_e = _ear_height(p)
    pieces = [(_bail_path(p)[8:-8], p.wire_radius + 0.001)]
    if p.grip:
        pieces.append((_grip_path(p), _grip_radius(p) + 0.001))
    largest = 0.0
    for angle in np.linspace(0.0, 2.8, 113)[1:]:
        for points, clearance in pieces:
            moved = _turn(points, angle, z_e)
            if _touches_body(p, moved, clearance) or moved[:, 2].min() < clearance:
                return p.handle_tilt * largest
        largest = angle
    return p.handle_tilt * largest


def _turn(points: np.ndarray, angle: float, z_pivot: float) -> np.ndarray:
    """(N, 3) points of the pivot frame turned by ``angle`` about the x axis and lifted to the pivot height."""
    c, s = np.cos(angle), np.sin(angle)
    y = c * points[:, 1] - s * points[:, 2]
    z = s * points[:, 1] + c * points[:, 2]
    return np.stack([points[:, 0], y, z + z_pivot], 1)


def build(p: BucketParams, body_mat: Material, wire_mat: Material, grip_mat: Material) -> ObjectAsset:
    """Build the bucket's parts from its parameters."""
    segments = 64 if p.shape == "round" else 96
    body = _squarify(revolve(_body_profile(p), segments=segments), p)
    body = trimesh.util.concatenate([body, *_ears(p)])
    pose = (rotation((1.0, 0.0, 0.0), _tilt_angle(p)), translation((0.0, 0.0, _ear_height(p))))
    bail = placed(tube(_bail_path(p), p.wire_radius, sides=14), *pose)
    parts = [
        Part("body", "contain", body, (body_mat,)),
        Part("bail", "grasp", bail, (wire_mat,)),
    ]
    if p.grip:
        path = _grip_path(p)
        u = np.linspace(0.0, 1.0, len(path))
        radius = _grip_radius(p) * (0.8 + 0.2 * np.sin(np.pi * u) ** 0.5)
        parts.append(Part("grip", "grasp", placed(tube(path, radius, sides=20), *pose), (grip_mat,)))
    return ObjectAsset(category="bucket", parts=parts, params=asdict(p))


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random bucket."""
    params = sample_params(rng)
    body = random_material(rng, pattern_probability=0.15, period=(0.01, 0.05)) if rng.uniform() < 0.75 else metal(rng)
    grip = Material(color=random_color(rng, value=(0.1, 0.7)))
    return build(params, body, metal(rng), grip)
