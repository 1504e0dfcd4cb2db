"""Bottles: a body (grasp), a neck and a mouth (pour) and, often, a cap (open).

Orientation: the bottle stands on its flat base at z = 0 and rises along +z, cap up; its axis is the z axis, and
an oval or flattened body has its wide side along x.

Shape parameters (metres unless noted): body radius, wall height, base fillet, waist depth and height (a grip
pinch), shoulder length, roundness and dome (the shoulder's profile curve), body squareness and aspect (the
cross-section), neck length, radius and taper, lip height and thickness, cap height, label band.
Styles: ``wine`` (tall body, long neck) or ``water`` (short neck, often a waist and a neck ring) profile; ``round``
or ``square`` cross-section; cap ``screw`` (ribbed), ``capsule`` (foil sleeve), ``cork`` or ``none`` (then the
bottle has no ``open`` part); with or without a label.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import trimesh

from affnerf.objects.appearance import metal, random_color, random_material, shade
from affnerf.objects.asset import Material, ObjectAsset, Part
from affnerf.objects.categories._loft import loft
from affnerf.objects.primitives import revolve, superellipse, sweep

#: Points around the body's cross-section.
_SECTION_POINTS = 64


@dataclass(frozen=True)
class BottleParams:
    """Shape and style parameters of a bottle (metres)."""

    body_radius: float  # half the body's width (along x)
    wall_height: float  # height of the body below the shoulder
    base_fillet: float  # radius of the rounded edge at the base
    waist_depth: float  # relative narrowing of a grip waist, 0 = none
    waist_height: float  # height of the waist as a fraction of the wall height
    shoulder_length: float  # height over which the body narrows to the neck
    shoulder_roundness: float  # superellipse exponent of the shoulder: ~1.3 conical, 2 round, 4 flat
    shoulder_dome: float  # 0 = S-shaped (cosine) shoulder, 1 = pure superellipse dome
    squareness: float  # superellipse exponent of a square body's section (2 = round)
    aspect: float  # depth / width of the body's section (1 = round, < 1 flattened)
    neck_length: float  # from the end of the shoulder to the mouth
    neck_radius: float  # at the neck's base
    neck_taper: float  # relative narrowing of the neck towards the mouth
    lip_height: float  # height of the mouth's lip ring
    lip_thickness: float  # how far the lip stands out from the neck
    cap_height: float  # height of a cap or cork above the mouth
    label_low: float  # label band's lower edge, fraction of the wall height
    label_high: float  # label band's upper edge, fraction of the wall height
    profile: Literal["wine", "water"]
    section: Literal["round", "square"]
    cap: Literal["screw", "capsule", "cork", "none"]
    neck_ring: bool  # a support ring below the mouth (PET water bottles)
    label: bool


def sample_params(rng: np.random.Generator) -> BottleParams:
    """Draw bottle parameters."""
    profile = ("wine", "water")[rng.integers(2)]
    wine = profile == "wine"
    radius = rng.uniform(0.033, 0.045) if wine else rng.uniform(0.026, 0.05)
    wall = radius * (rng.uniform(3.2, 5.0) if wine else rng.uniform(2.0, 5.0))
    neck_r = radius * (rng.uniform(0.34, 0.44) if wine else rng.uniform(0.3, 0.5))
    low = rng.uniform(0.2, 0.45)
    caps = ("capsule", "cork", "none") if wine else ("screw", "screw", "none")
    return BottleParams(
        body_radius=radius,
        wall_height=wall,
        base_fillet=radius * rng.uniform(0.05, 0.3),
        waist_depth=rng.uniform(0.0, 0.02) if wine else rng.uniform(0.0, 0.12),
        waist_height=rng.uniform(0.45, 0.75),
        shoulder_length=radius * (rng.uniform(0.7, 1.6) if wine else rng.uniform(0.6, 2.2)),
        shoulder_roundness=rng.uniform(1.4, 3.5),
        shoulder_dome=rng.uniform(0.0, 1.0),
        squareness=rng.uniform(3.0, 7.0),
        aspect=1.0 if rng.uniform() < 0.6 else rng.uniform(0.6, 0.95),
        neck_length=radius * (rng.uniform(1.8, 2.8) if wine else rng.uniform(0.35, 0.8)),
        neck_radius=neck_r,
        neck_taper=rng.uniform(0.0, 0.15) if wine else rng.uniform(0.0, 0.05),
        lip_height=neck_r * rng.uniform(0.35, 0.7),
        lip_thickness=neck_r * rng.uniform(0.08, 0.2),
        cap_height=neck_r * rng.uniform(0.9, 1.8),
        label_low=low,
        label_high=low + rng.uniform(0.25, 0.5),
        profile=profile,
        section=("round", "square")[rng.integers(3) // 2],  # one in three is square
        cap=caps[rng.integers(len(caps))],
        neck_ring=bool(not wine and rng.uniform() < 0.6),
        label=bool(rng.uniform() < 0.65),
    )


def _smoothstep(s: np.ndarray) -> np.ndarray:
    """3s² - 2s³ on [0, 1], clipped."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


def body_profile(p: BottleParams, n_wall: int = 40, n_shoulder: int = 32) -> np.ndarray:
    """(n_wall + n_shoulder, 2) (radius, z) outline of the body from the base (z = 0) to the neck.

    The wall is straight apart from a rounded base edge and an optional waist; the shoulder blends a superellipse
    dome with an S-shaped cosine.
    """
    r_big, f = p.body_radius, p.base_fillet
    z = np.concatenate([f * (1.0 - np.cos(np.linspace(0.0, np.pi / 2, 8))), np.linspace(f, p.wall_height, n_wall - 8)])
    z = np.unique(z)
    fillet = np.sqrt(np.clip(f**2 - np.clip(f - z, 0.0, None) ** 2, 0.0, None))
    r = r_big - f + fillet
    waist_z, waist_w = p.waist_height * p.wall_height, 0.12 * p.wall_height
    r = r * (1.0 - p.waist_depth * np.exp(-(((z - waist_z) / waist_w) ** 2)))
    s = np.linspace(0.0, 1.0, n_shoulder + 1)[1:]
    e = p.shoulder_roundness
    dome = (1.0 - s**e) ** (1.0 / e)
    s_curve = 0.5 + 0.5 * np.cos(np.pi * s)
    blend = p.shoulder_dome * dome + (1.0 - p.shoulder_dome) * s_curve
    r_sh = p.neck_radius + (r_big - p.neck_radius) * blend
    z_sh = p.wall_height + s * p.shoulder_length
    return np.concatenate([np.stack([r, z], 1), np.stack([r_sh, z_sh], 1)])


def _body(p: BottleParams) -> trimesh.Trimesh:
    """The body as a loft whose section rounds off from the body's shape to a circle at the neck."""
    profile = body_profile(p)
    z = profile[:, 1]
    to_neck = _smoothstep((z - p.wall_height) / p.shoulder_length)  # 0 on the wall, 1 at the neck
    exponent = 2.0 if p.section == "round" else p.squareness
    rings = []
    for (r, zi), t in zip(profile, to_neck, strict=True):
        e = exponent + (2.0 - exponent) * t
        b = p.aspect + (1.0 - p.aspect) * t
        xy = superellipse(r, r * b, e, _SECTION_POINTS)
        rings.append(np.column_stack([xy, np.full(_SECTION_POINTS, zi)]))
    return loft(np.stack(rings))


def neck_top(p: BottleParams) -> float:
    """Height of the mouth's top edge."""
    return p.wall_height + p.shoulder_length + p.neck_length


def _neck(p: BottleParams) -> trimesh.Trimesh:
    """The neck: a tapering cylinder sunk into the shoulder, with an optional support ring."""
    z0 = p.wall_height + 0.4 * p.shoulder_length
    z_top = neck_top(p) - 0.35 * p.lip_height  # the top sits below the lip, so the mouth looks open
    r0, r1 = p.neck_radius, p.neck_radius * (1.0 - p.neck_taper)
    z_neck = p.wall_height + p.shoulder_length
    points = [(r0, z0), (r0, z_neck)]
    if p.neck_ring:
        zr, w = neck_top(p) - p.lip_height - 0.6 * p.neck_radius, 0.12 * p.neck_radius
        rr = r1 + 2.2 * p.lip_thickness
        points += [(r1, zr - w), (rr, zr - 0.3 * w), (rr, zr + 0.3 * w), (r1, zr + w)]
    points.append((r1, z_top))
    return revolve(np.array(points), segments=40)


def _mouth(p: BottleParams) -> trimesh.Trimesh:
    """The lip: a ring around the neck's top with a rounded outer edge."""
    r_in = p.neck_radius * (1.0 - p.neck_taper) * 0.72
    r_out = p.neck_radius * (1.0 - p.neck_taper) + p.lip_thickness
    z1 = neck_top(p)
    z0 = z1 - p.lip_height
    c = min(0.3 * p.lip_height, 0.8 * p.lip_thickness)
    loop = [(r_in, z0), (r_out - c, z0), (r_out, z0 + c), (r_out, z1 - c), (r_out - c, z1), (r_in, z1)]
    return revolve(np.array(loop), segments=40, closed=True)


def _cap(p: BottleParams) -> trimesh.Trimesh:
    """The closure: a ribbed screw cap, a foil capsule over the neck's top, or a cork in the mouth."""
    r_lip = p.neck_radius * (1.0 - p.neck_taper) + p.lip_thickness
    z1 = neck_top(p)
    if p.cap == "cork":
        r = p.neck_radius * (1.0 - p.neck_taper) * 0.8
        return revolve(np.array([[r, z1 - p.lip_height], [r, z1 + 0.5 * p.cap_height]]), segments=32)
    if p.cap == "capsule":
        length = 0.55 * p.neck_length
        r = r_lip + 0.0008
        profile = [(r, z1 - length), (r, z1 + 0.002), (0.9 * r, z1 + 0.0035)]
        return revolve(np.array(profile), segments=40)
    r = r_lip + 0.0015
    z0 = z1 - 0.45 * p.cap_height
    top = z1 + 0.55 * p.cap_height
    t = np.linspace(0.0, 2.0 * np.pi, 96, endpoint=False)
    ribs = 1.0 + 0.025 * (np.cos(24 * t) > 0)
    section = np.stack([ribs * np.cos(t), ribs * np.sin(t)], 1)
    path = np.array([[0.0, 0.0, z0], [0.0, 0.0, top - 0.0015], [0.0, 0.0, top]])
    return sweep(path, section, scales=np.array([r, r, r - 0.0015]))


def _band_faces(mesh: trimesh.Trimesh, z_low: float, z_high: float) -> np.ndarray:
    """(F,) 1 for faces whose centroid lies in the height band, else 0 (a material index)."""
    zc = mesh.triangles_center[:, 2]
    return ((zc > z_low) & (zc < z_high)).astype(np.int64)


def build(p: BottleParams, glass: Material, label: Material, closure: Material) -> ObjectAsset:
    """Build the bottle's parts from its parameters.

    Args:
        p: the parameters.
        glass: the body, neck and mouth's material.
        label: the label band's material (used when ``p.label``).
        closure: the cap's material (unused without a cap).
    """
    body = _body(p)
    body_mats: tuple[Material, ...] = (glass,)
    body_faces = None
    if p.label:
        body_mats = (glass, label)
        body_faces = _band_faces(body, p.label_low * p.wall_height, p.label_high * p.wall_height)
    neck = _neck(p)
    opening = Material(color=shade(glass.color, 0.25))  # the dark inside seen through the mouth
    neck_faces = (neck.triangles_center[:, 2] > neck_top(p) - 0.36 * p.lip_height).astype(np.int64)
    parts = [
        Part("body", "grasp", body, materials=body_mats, face_material=body_faces),
        Part("neck", "pour", neck, materials=(glass, opening), face_material=neck_faces),
        Part("mouth", "pour", _mouth(p), materials=(glass,)),
    ]
    if p.cap != "none":
        parts.append(Part("cap", "open", _cap(p), materials=(closure,)))
    return ObjectAsset(category="bottle", parts=parts, params=asdict(p))


def _glass(rng: np.random.Generator, profile: str) -> Material:
    """A bottle colour: green, amber or dark glass for wine, clear-blue or any plastic colour for water."""
    if profile == "wine":
        hue = ((0.22, 0.4), (0.05, 0.11), (0.0, 1.0))[rng.integers(3)]
        return Material(color=random_color(rng, hue=hue, saturation=(0.4, 0.9), value=(0.15, 0.5)))
    if rng.uniform() < 0.5:
        return Material(color=random_color(rng, hue=(0.5, 0.62), saturation=(0.1, 0.45), value=(0.7, 0.95)))
    return Material(color=random_color(rng))


def _closure(rng: np.random.Generator, cap: str) -> Material:
    """A cap's material: cork brown, a foil colour or metal for a capsule, any plastic colour for a screw cap."""
    if cap == "cork":
        return Material(color=random_color(rng, hue=(0.07, 0.11), saturation=(0.3, 0.55), value=(0.55, 0.8)))
    if cap == "capsule" and rng.uniform() < 0.4:
        return metal(rng)
    return random_material(rng, pattern_probability=0.0)


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random bottle."""
    params = sample_params(rng)
    glass = _glass(rng, params.profile)
    label = random_material(rng, pattern_probability=0.4, period=(0.004, 0.015))
    return build(params, glass, label, _closure(rng, params.cap))
