"""Screwdrivers: a handle (grasp), a shaft and a tip (screw); the shaft lies along +x.

Shape parameters: handle length, handle radius, handle bulge and end taper (profile curve), shaft length, shaft
radius, tip length; styles: flat or Phillips tip, round or fluted handle, with or without a collar.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import trimesh

from affnerf.objects.appearance import metal, random_material
from affnerf.objects.asset import Material, ObjectAsset, Part
from affnerf.objects.primitives import placed, revolve, rotation, smooth_curve, superellipse, sweep

#: Rotation taking the build axis (+z) onto the canonical main axis (+x).
_Z_TO_X = rotation((0.0, 1.0, 0.0), np.pi / 2)


@dataclass(frozen=True)
class ScrewdriverParams:
    """Shape parameters of a screwdriver (metres)."""

    handle_length: float
    handle_radius: float
    handle_bulge: float  # relative widening of the handle's middle, 0 = straight
    handle_taper: float  # relative narrowing at the shaft end of the handle
    shaft_length: float
    shaft_radius: float
    tip_length: float
    tip: Literal["flat", "phillips"]
    grip: Literal["round", "fluted"]
    collar: bool


def sample_params(rng: np.random.Generator) -> ScrewdriverParams:
    """Draw screwdriver parameters."""
    handle_radius = rng.uniform(0.009, 0.019)
    return ScrewdriverParams(
        handle_length=rng.uniform(0.07, 0.13),
        handle_radius=handle_radius,
        handle_bulge=rng.uniform(0.0, 0.3),
        handle_taper=rng.uniform(0.1, 0.45),
        shaft_length=rng.uniform(0.05, 0.2),
        shaft_radius=rng.uniform(0.0018, min(0.0045, 0.3 * handle_radius)),
        tip_length=rng.uniform(0.006, 0.016),
        tip=("flat", "phillips")[rng.integers(2)],
        grip=("round", "fluted")[rng.integers(2)],
        collar=bool(rng.integers(2)),
    )


def _handle_profile(p: ScrewdriverParams, n: int = 24) -> np.ndarray:
    """(n, 2) (radius, z) profile of the handle from its butt (z = 0) to the shaft end."""
    r, length = p.handle_radius, p.handle_length
    control = np.array(
        [
            [0.82 * r, 0.0],
            [r, 0.12 * length],
            [r * (1.0 + p.handle_bulge), 0.5 * length],
            [r, 0.85 * length],
            [r * (1.0 - p.handle_taper), length],
        ]
    )
    curve = smooth_curve(control[:, ::-1], n)[:, ::-1]  # spline in z, radius as its function
    curve[:, 0] = np.maximum(curve[:, 0], 0.3 * r)
    return curve


def _handle(p: ScrewdriverParams) -> trimesh.Trimesh:
    profile = _handle_profile(p)
    if p.grip == "round":
        return revolve(profile, segments=40)
    # Fluted grip: a lobed cross-section swept along the axis, scaled by the profile.
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    lobes = 1.0 + 0.08 * np.cos(6 * t)
    section = np.stack([lobes * np.cos(t), lobes * np.sin(t)], 1)
    path = np.stack([np.zeros(len(profile)), np.zeros(len(profile)), profile[:, 1]], 1)
    return sweep(path, section, scales=profile[:, 0] / 1.08)


def _tip(p: ScrewdriverParams, z0: float) -> trimesh.Trimesh:
    n = 10
    z = np.linspace(z0, z0 + p.tip_length, n)
    s = np.linspace(0.0, 1.0, n)
    path = np.stack([np.zeros(n), np.zeros(n), z], 1)
    r = p.shaft_radius
    if p.tip == "flat":
        section = superellipse(1.0, 1.0, 8.0, 32)
        scales = np.stack([r * (1.0 + 0.4 * s), r * (1.0 - 0.75 * s)], 1)  # fans out and flattens
        return sweep(path, section, scales=scales)
    # Phillips: a plus-shaped section (star-shaped about its centre) tapering to a point.
    w = 0.28
    section = np.array(
        [(1, -w), (1, w), (w, w), (w, 1), (-w, 1), (-w, w), (-1, w), (-1, -w), (-w, -w), (-w, -1), (w, -1), (w, -w)],
        dtype=np.float64,
    )
    return sweep(path, section, scales=r * (1.0 - 0.85 * s))


def build(p: ScrewdriverParams, handle_mat: Material, steel: Material) -> ObjectAsset:
    """Build the screwdriver's parts from its parameters."""
    handle = _handle(p)
    insert = 0.25 * p.handle_length  # the shaft goes into the handle, so the parts overlap
    z_shaft = p.handle_length - insert
    shaft_top = p.handle_length + p.shaft_length
    shaft_profile = np.array([[p.shaft_radius, z_shaft], [p.shaft_radius, shaft_top]])
    if p.collar:
        c = p.handle_length
        collar_r = min(p.handle_radius * (1.0 - p.handle_taper) * 0.9, 2.5 * p.shaft_radius)
        collar_r = max(collar_r, 1.4 * p.shaft_radius)
        shaft_profile = np.array(
            [
                [p.shaft_radius, z_shaft],
                [p.shaft_radius, c - 0.002],
                [collar_r, c],
                [collar_r, c + 0.006],
                [p.shaft_radius, c + 0.01],
                [p.shaft_radius, shaft_top],
            ]
        )
    shaft = revolve(shaft_profile, segments=20)
    tip = _tip(p, shaft_top - 0.0005)
    parts = [
        Part("handle", "grasp", placed(handle, _Z_TO_X), materials=(handle_mat,)),
        Part("shaft", "screw", placed(shaft, _Z_TO_X), materials=(steel,)),
        Part("tip", "screw", placed(tip, _Z_TO_X), materials=(steel,)),
    ]
    return ObjectAsset(category="screwdriver", parts=parts, params=asdict(p))


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random screwdriver."""
    params = sample_params(rng)
    return build(params, random_material(rng), metal(rng))
