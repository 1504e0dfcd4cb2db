"""Pens: a barrel and a clip (grasp), a cap (open) and a writing tip (write).

Canonical orientation: the pen's axis along +x with the writing tip at the +x end; the clip, when there is one,
sits on top (+z).

Shape parameters: barrel length, barrel radius, body taper (back to front), grip swelling or waist, front cone
length and taper (the barrel's profile curve), tip length, cap length, cap radius (relative to the barrel), clip
length, clip width. Styles: round or hexagonal barrel; no cap (a click pen with a push button), a cap posted on
the back end or a cap on the tip; with or without a clip (a capped pen carries its clip on the cap). Appearance:
barrel colour or pattern, sometimes a differently coloured grip zone, steel or dark tip, cap and clip colours.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import trimesh

from affnerf.objects.appearance import metal, random_color, random_material
from affnerf.objects.asset import Material, ObjectAsset, Part
from affnerf.objects.primitives import placed, revolve, rotation, smooth_curve, superellipse, sweep, translation

#: Build frame (pen axis +z, clip on +x) to canonical frame (axis +x, clip on +z).
_TO_CANONICAL = (rotation((0.0, 0.0, 1.0), np.pi), rotation((0.0, 1.0, 0.0), np.pi / 2))
#: Half-turn about x: flips a part built along +z so that it points along -z.
_FLIP = rotation((1.0, 0.0, 0.0), np.pi)
#: Share of the barrel's length taken by the grip zone.
_GRIP_SHARE = 0.3


@dataclass(frozen=True)
class PenParams:
    """Shape parameters of a pen (metres)."""

    barrel_length: float  # from the back end to the start of the tip
    barrel_radius: float  # radius of the body (apothem of a hexagonal barrel)
    body_taper: float  # relative narrowing of the body from back to front (negative widens)
    front_length: float  # share of the barrel taken by the front cone
    front_taper: float  # relative narrowing of the front cone
    grip: float  # relative swelling (negative: waist) of the grip zone behind the front cone
    tip_length: float  # length of the writing cone
    cap_length: float
    cap_radius: float  # cap radius relative to the barrel radius
    clip_length: float
    clip_width: float
    section: Literal["round", "hexagonal"]
    cap: Literal["none", "posted", "on_tip"]
    clip: bool


def sample_params(rng: np.random.Generator) -> PenParams:
    """Draw pen parameters."""
    barrel_length = rng.uniform(0.1, 0.145)
    barrel_radius = rng.uniform(0.0035, 0.0065)
    cap_length = rng.uniform(0.03, 0.058)
    return PenParams(
        barrel_length=barrel_length,
        barrel_radius=barrel_radius,
        body_taper=rng.uniform(-0.08, 0.18),
        front_length=rng.uniform(0.1, 0.3),
        front_taper=rng.uniform(0.2, 0.55),
        grip=rng.uniform(-0.08, 0.15) if rng.uniform() < 0.6 else 0.0,
        tip_length=rng.uniform(0.004, 0.014),
        cap_length=cap_length,
        cap_radius=rng.uniform(1.08, 1.3),
        clip_length=rng.uniform(0.45, 0.8) * cap_length,
        clip_width=rng.uniform(0.5, 1.0) * barrel_radius,
        section=("round", "hexagonal")[rng.integers(2)],
        cap=("none", "posted", "on_tip")[rng.choice(3, p=(0.35, 0.4, 0.25))],
        clip=bool(rng.uniform() < 0.75),
    )


def _hexagon(rounding: float = 0.15, n: int = 72) -> np.ndarray:
    """(n, 2) hexagon with rounded corners and unit apothem, blended toward a circle by ``rounding``."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    sector = np.pi / 3.0
    r_poly = 1.0 / np.cos((t % sector) - sector / 2.0)
    r = (1.0 - rounding) * r_poly + rounding
    return np.stack([r * np.cos(t), r * np.sin(t)], 1)


def _barrel_profile(p: PenParams, n: int = 48) -> np.ndarray:
    """(K, 2) (radius, z) outline of the barrel from its back end (z = 0, or the push button below it) to z = length.

    The body tapers linearly, swells or narrows smoothly in the grip zone just behind the front cone, and the cone
    eases into the tip. z increases strictly along the outline, so it also serves as the scales of a swept section.
    """
    r, length = p.barrel_radius, p.barrel_length
    z_front = length * (1.0 - p.front_length)
    z = np.linspace(0.003, length, n)
    body = r * (1.0 - p.body_taper * np.minimum(z / z_front, 1.0))
    grip_start = z_front - _GRIP_SHARE * length
    u = np.clip((z - grip_start) / (z_front - grip_start), 0.0, 1.0)
    body = body * (1.0 + p.grip * np.sin(np.pi * u) ** 2)
    s = np.clip((z - z_front) / (length - z_front), 0.0, 1.0)
    radius = body * (1.0 - p.front_taper * s**1.4)
    back = np.array([[0.86 * r, 0.0], [0.97 * r, 0.001]])
    profile = np.vstack([back, np.stack([radius, z], 1)])
    if p.cap != "none":
        return profile
    button_r, button_len = 0.5 * r, 0.002 + 1.2 * r
    button = np.array([[0.8 * button_r, -button_len], [button_r, -button_len + 0.001], [button_r, -0.0004]])
    return np.vstack([button, profile])


def _grip_faces(mesh: trimesh.Trimesh, p: PenParams) -> np.ndarray:
    """(F,) 1 for the barrel's faces in the grip zone (build frame, along z), 0 elsewhere."""
    z_front = p.barrel_length * (1.0 - p.front_length)
    z = mesh.triangles_center[:, 2]
    return ((z > z_front - _GRIP_SHARE * p.barrel_length) & (z < z_front)).astype(np.int64)


def _barrel(p: PenParams) -> trimesh.Trimesh:
    """The barrel (build frame: along +z), revolved when round, a swept rounded hexagon otherwise."""
    profile = _barrel_profile(p)
    if p.section == "round":
        return revolve(profile, segments=40)
    path = np.stack([np.zeros(len(profile)), np.zeros(len(profile)), profile[:, 1]], 1)
    return sweep(path, _hexagon(), scales=profile[:, 0] / 1.02)


def _tip(p: PenParams) -> trimesh.Trimesh:
    """The writing cone with its ball point, starting a little inside the barrel's front end."""
    z0 = p.barrel_length
    r0 = 0.92 * p.barrel_radius * (1.0 - p.body_taper) * (1.0 - p.front_taper)
    ball = 0.00045
    s = np.linspace(0.0, 1.0, 10)
    cone = np.stack([ball + (r0 - ball) * (1.0 - s) ** 1.6, z0 + s * p.tip_length], 1)
    dome = np.array([[0.6 * ball, z0 + p.tip_length + 0.6 * ball], [0.0, z0 + p.tip_length + ball]])
    return revolve(np.vstack([[r0, z0 - 0.002], cone, dome]), segments=28)


def _cap(p: PenParams) -> trimesh.Trimesh:
    """The cap in its own frame: open end at z = 0, domed closed end at z = cap_length.

    It is solid: whatever it covers is hidden, so it needs no inside.
    """
    rc = p.cap_radius * p.barrel_radius
    length = p.cap_length
    profile = np.array(
        [
            [rc, 0.0],
            [1.02 * rc, 0.5 * length],
            [0.97 * rc, length - 0.5 * rc],
            [0.75 * rc, length - 0.12 * rc],
            [0.4 * rc, length],
        ]
    )
    return revolve(profile, segments=40)


def _clip(p: PenParams, radius: float) -> trimesh.Trimesh:
    """A clip in its own frame: fixed at z = 0, running along +z on the +x side of a body of ``radius``."""
    th = 0.0007
    gap = 0.0006 + 0.5 * th
    length = p.clip_length
    control = np.array(
        [
            [radius - 0.0008, 0.0],
            [radius + 0.5 * gap, 0.002],
            [radius + gap, 0.006],
            [radius + gap, 0.6 * length],
            [radius + 0.5 * gap, length - 0.002],
            [radius + 0.3 * gap, length],
        ]
    )
    xz = smooth_curve(control, 40)
    path = np.stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]], 1)
    section = superellipse(0.5 * th, 0.5 * p.clip_width, 4.0, 24)
    taper = np.linspace(1.0, 0.8, len(path))
    return sweep(path, section, scales=np.stack([np.ones_like(taper), taper], 1))


def _cap_pose(p: PenParams) -> tuple[np.ndarray, ...]:
    """Transforms placing the cap (and its clip) on the pen in the build frame."""
    if p.cap == "posted":  # pushed over the back end, closed end pointing back
        return (_FLIP, translation((0.0, 0.0, 0.35 * p.cap_length)))
    z_open = p.barrel_length + p.tip_length + 0.003 - p.cap_length
    return (translation((0.0, 0.0, z_open)),)


def build(
    p: PenParams,
    barrel_mat: Material,
    tip_mat: Material,
    cap_mat: Material,
    clip_mat: Material,
    grip_mat: Material | None = None,
) -> ObjectAsset:
    """Build the pen's parts from its parameters; ``grip_mat``, when given, covers the barrel's grip zone."""
    barrel = _barrel(p)
    grip_faces = None if grip_mat is None else _grip_faces(barrel, p)
    barrel_mats = (barrel_mat,) if grip_mat is None else (barrel_mat, grip_mat)
    parts = [
        Part("barrel", "grasp", placed(barrel, *_TO_CANONICAL), materials=barrel_mats, face_material=grip_faces),
        Part("tip", "write", placed(_tip(p), *_TO_CANONICAL), materials=(tip_mat,)),
    ]
    if p.cap != "none":
        pose = _cap_pose(p)
        parts.append(Part("cap", "open", placed(_cap(p), *pose, *_TO_CANONICAL), materials=(cap_mat,)))
        if p.clip:
            clip = placed(_clip(p, p.cap_radius * p.barrel_radius), _FLIP, translation((0, 0, p.cap_length - 0.003)))
            parts.append(Part("clip", "grasp", placed(clip, *pose, *_TO_CANONICAL), materials=(clip_mat,)))
    elif p.clip:
        clip = placed(_clip(p, p.barrel_radius), translation((0.0, 0.0, 0.003)))
        parts.append(Part("clip", "grasp", placed(clip, *_TO_CANONICAL), materials=(clip_mat,)))
    return ObjectAsset(category="pen", parts=parts, params=asdict(p))


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random pen."""
    params = sample_params(rng)
    barrel = random_material(rng, pattern_probability=0.2, period=(0.004, 0.02))
    tip = metal(rng) if rng.uniform() < 0.6 else Material(color=random_color(rng, value=(0.1, 0.4)))
    cap = barrel if rng.uniform() < 0.5 else Material(color=random_color(rng))
    clip = metal(rng) if rng.uniform() < 0.6 else cap
    grip = Material(color=random_color(rng, value=(0.1, 0.6))) if rng.uniform() < 0.35 else None
    return build(params, barrel, tip, cap, clip, grip)
