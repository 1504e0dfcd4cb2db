"""Scissors: two handles with finger rings (grasp) and two blades (cut), lying flat, blades pointing along +x.

Canonical orientation: the scissors lie in the xy plane (thickness along z, +z up) with the pivot near the middle,
the blades pointing along +x and the handles along -x. The upper half (blade and handle on top, z > 0) has its
ring on the -y side; opening the scissors turns the upper half counter-clockwise about the pivot (+z) and the lower
half clockwise, so the blade tips move apart in y.

Shape parameters: blade length, blade width, spine convexity (profile curve of the blade), blade curvature (bend of
both blades), handle length, ring size, ring ellipticity, ring wall, blade thickness, handle thickness, opening
angle, loop scale (size of the large finger loop). Styles: round or oval rings; symmetric (two like rings) or
asymmetric (a thumb ring and a large finger loop); pointed or blunt tips.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import shapely.affinity
import shapely.geometry as geo
import trimesh

from affnerf.objects.appearance import metal, random_material
from affnerf.objects.asset import Material, ObjectAsset, Part
from affnerf.objects.primitives import cylinder, extrude, placed, smooth_curve, superellipse, translation


@dataclass(frozen=True)
class ScissorsParams:
    """Shape parameters of a pair of scissors (metres, radians)."""

    blade_length: float  # pivot to tip
    blade_width: float  # width of one blade at the pivot
    spine_convexity: float  # exponent of the spine's taper: below 1 bulges, 1 is straight
    blade_curve: float  # sideways bend of both blades at the tip, relative to the blade length
    handle_length: float  # pivot to the centre of the (thumb) ring, along -x
    ring_radius: float  # outer half-height (y) of the thumb ring
    ring_ellipticity: float  # outer half-length (x) over half-height (y) of the thumb ring
    ring_wall: float  # width of the ring's band
    blade_thickness: float
    handle_thickness: float
    opening_angle: float  # angle between the two halves; 0 = closed
    loop_scale: float  # length of the lower half's loop relative to the thumb ring (1 when symmetric)
    rings: Literal["round", "oval"]
    layout: Literal["symmetric", "asymmetric"]
    tips: Literal["pointed", "blunt"]


def sample_params(rng: np.random.Generator) -> ScissorsParams:
    """Draw scissors parameters."""
    rings = ("round", "oval")[rng.integers(2)]
    layout = ("symmetric", "asymmetric")[rng.integers(2)]
    blade_length = rng.uniform(0.045, 0.12)
    ring_radius = rng.uniform(0.0105, 0.016)
    ring_ellipticity = rng.uniform(0.95, 1.15) if rings == "round" else rng.uniform(1.3, 1.9)
    max_loop = max(1.45, min(2.2, 0.034 / (ring_radius * ring_ellipticity)))  # a finger loop at most ~7 cm long
    return ScissorsParams(
        blade_length=blade_length,
        blade_width=rng.uniform(0.11, 0.2) * blade_length + 0.004,
        spine_convexity=rng.uniform(0.45, 1.05),
        blade_curve=rng.uniform(-0.02, 0.06) if rng.uniform() < 0.4 else 0.0,
        handle_length=rng.uniform(0.5, 0.75) * blade_length + 0.015,
        ring_radius=ring_radius,
        ring_ellipticity=ring_ellipticity,
        ring_wall=rng.uniform(0.0028, min(0.0055, 0.33 * ring_radius)),
        blade_thickness=rng.uniform(0.0012, 0.0025),
        handle_thickness=rng.uniform(0.004, 0.008),
        opening_angle=rng.uniform(0.0, 0.6) if rng.uniform() < 0.7 else 0.0,
        loop_scale=rng.uniform(1.4, max_loop) if layout == "asymmetric" else 1.0,
        rings=rings,
        layout=layout,
        tips=("pointed", "blunt")[rng.integers(2)],
    )


def _blade_outline(p: ScissorsParams, n: int = 40) -> np.ndarray:
    """(2n, 2) outline of the upper blade, closed state: straight cutting edge below, tapering spine above.

    The pivot is at the origin, half-way across the blade's base; the tip is at (blade_length, 0).
    """
    s = np.linspace(0.0, 1.0, n)
    half = 0.5 * p.blade_width
    edge = np.stack([s * p.blade_length, -half * (1.0 - s)], 1)
    spine = np.stack([s * p.blade_length, half * (1.0 - s) ** p.spine_convexity], 1)
    return np.vstack([edge, spine[::-1][:-1]])


def _bend(xy: np.ndarray, p: ScissorsParams) -> np.ndarray:
    """(N, 2) points shifted sideways by the blades' bend, which grows with the square of x past the pivot."""
    x = np.clip(xy[:, 0] / p.blade_length, 0.0, None)
    return xy + np.stack([np.zeros(len(xy)), p.blade_curve * p.blade_length * x**2], 1)


def _ring_geometry(p: ScissorsParams, side: float) -> tuple[np.ndarray, float, float]:
    """Centre (2,), outer half-length and half-height of a half's ring; ``side`` is -1 (upper half) or +1 (lower)."""
    b = p.ring_radius
    a = b * p.ring_ellipticity
    if side > 0 and p.layout == "asymmetric":
        a_loop, b_loop = a * p.loop_scale, b * 1.1
        centre = np.array([-p.handle_length - 0.6 * (a_loop - a), side * (b_loop + 0.0015)])
        return centre, a_loop, b_loop
    return np.array([-p.handle_length, side * (b + 0.0015)]), a, b


def _shank_half_width(p: ScissorsParams) -> float:
    """Half the width of a handle's shank."""
    return 0.45 * p.ring_wall + 0.0022


def _handle_shape(p: ScissorsParams, side: float) -> geo.Polygon:
    """The 2D handle of one half (closed state): a shank from behind the pivot bent into a finger ring."""
    centre, a, b = _ring_geometry(p, side)
    start = np.array([-0.45 * p.blade_width - 0.004, 0.25 * side * p.blade_width])
    mid = np.array([0.55 * (start[0] + centre[0] + a), side * 0.35 * b])
    shank = geo.LineString(smooth_curve(np.array([start, mid, centre]), 24)).buffer(_shank_half_width(p))
    outer = geo.Polygon(superellipse(a, b, 2.3, 64) + centre)
    inner = outer.buffer(-p.ring_wall)
    return shank.union(outer).difference(inner)


def _blade_shape(p: ScissorsParams, side: float) -> geo.Polygon:
    """The 2D blade of one half (closed state) with its rounded base around the pivot and a tang into the handle."""
    outline = _blade_outline(p)
    if side > 0:  # the lower blade mirrors the upper one
        outline = outline * np.array([1.0, -1.0])
    blade = geo.Polygon(_bend(outline, p))
    if p.tips == "blunt":
        radius = 0.38 * p.blade_width
        x_c = p.blade_length - radius
        y_c = p.blade_curve * p.blade_length * (x_c / p.blade_length) ** 2
        nose = geo.box(-1.0, -1.0, x_c, 1.0).union(geo.Point(x_c, y_c).buffer(radius, 32))
        blade = blade.intersection(nose)
    base = geo.Point(0.0, 0.0).buffer(0.55 * p.blade_width, 32)
    centre, _, _ = _ring_geometry(p, side)
    tang_width = min(0.2 * p.blade_width, 0.8 * _shank_half_width(p))
    tang = geo.LineString([(0.0, 0.0), tuple(0.25 * centre)]).buffer(tang_width)
    shape = blade.union(base).union(tang).buffer(-0.0003).buffer(0.0003)
    return max(getattr(shape, "geoms", [shape]), key=lambda g: g.area)


def _slab(shape: geo.Polygon, z0: float, thickness: float, angle: float) -> trimesh.Trimesh:
    """Extrude a 2D shape from z0 to z0 + thickness and turn it by ``angle`` about the pivot (+z axis)."""
    shape = shapely.affinity.rotate(shape, angle, origin=(0.0, 0.0), use_radians=True)
    shape = shape.simplify(1e-5)  # drops near-duplicate vertices that would collapse when the mesh is merged
    outline = np.asarray(shape.exterior.coords)[:-1]
    holes = [np.asarray(r.coords)[:-1] for r in shape.interiors]
    return placed(extrude(outline, thickness, holes), translation((0.0, 0.0, z0)))


def _pivot(p: ScissorsParams) -> trimesh.Trimesh:
    """The pivot screw through both blades, with a head just proud of each side."""
    t = p.blade_thickness
    return placed(cylinder(0.18 * p.blade_width, 2.0 * t + 0.0012, 24), translation((0.0, 0.0, -t - 0.0006)))


def build(p: ScissorsParams, handle_mat: Material, steel: Material) -> ObjectAsset:
    """Build the scissors' parts from its parameters."""
    t, h = p.blade_thickness, p.handle_thickness
    half = 0.5 * p.opening_angle
    upper_blade = trimesh.util.concatenate([_slab(_blade_shape(p, -1.0), 0.0, t, half), _pivot(p)])
    parts = [
        Part("handle_upper", "grasp", _slab(_handle_shape(p, -1.0), 0.5 * t - 0.5 * h, h, half), (handle_mat,)),
        Part("handle_lower", "grasp", _slab(_handle_shape(p, 1.0), -0.5 * t - 0.5 * h, h, -half), (handle_mat,)),
        Part("blade_upper", "cut", upper_blade, (steel,)),
        Part("blade_lower", "cut", _slab(_blade_shape(p, 1.0), -t, t, -half), (steel,)),
    ]
    return ObjectAsset(category="scissors", parts=parts, params=asdict(p))


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random pair of scissors."""
    params = sample_params(rng)
    handle = random_material(rng, pattern_probability=0.15) if rng.uniform() < 0.85 else metal(rng)
    return build(params, handle, metal(rng))
