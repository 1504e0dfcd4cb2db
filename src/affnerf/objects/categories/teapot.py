"""Teapots: a body (contain), a spout (pour), a handle (grasp) and a lid (open).

Orientation: the teapot stands on its foot at z = 0 with its axis along +z; the spout points to +x and rises
towards its tip; a side handle is on the -x side; a top handle arches over the lid in the xz plane.

Shape parameters (metres unless noted): body radius, height, height of the widest point, foot and rim radii
(the body's profile curve), lobe depth; spout length, tip height, angle, bend, base radius and taper; handle
span, reach, thickness and skew; lid dome height and knob size.
Styles: ``round`` (squat) or ``tall`` body; ``side`` or ``top`` (over) handle; smooth or lobed (melon) body
(``lobes`` = 0 or 5..10); ``ball`` or ``flat`` knob.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import trimesh

from affnerf.objects.appearance import random_color, random_material
from affnerf.objects.asset import Material, ObjectAsset, Part
from affnerf.objects.categories._loft import loft
from affnerf.objects.primitives import ellipse, revolve, smooth_curve, sweep, tube


@dataclass(frozen=True)
class TeapotParams:
    """Shape and style parameters of a teapot (metres; fractions are of the body's radius or height)."""

    radius: float  # body radius at its widest point
    height: float  # body height, foot to rim
    widest: float  # height of the widest point, fraction of the height
    foot: float  # foot radius, fraction of the radius
    rim: float  # radius of the opening the lid sits in, fraction of the radius
    lobe_depth: float  # relative depth of the lobes of a melon body
    spout_length: float  # straight distance from where the spout leaves the body to its tip, fraction of the radius
    spout_tip: float  # height of the spout's tip, fraction of the height
    spout_angle: float  # elevation of the line from the spout's base to its tip, radians
    spout_bend: float  # sideways bow of the spout, fraction of its length (S-curve when > 0)
    spout_radius: float  # spout radius at the body, fraction of the radius
    spout_taper: float  # tip radius / base radius
    handle_span: float  # vertical distance between the handle's attachments, fraction of the height
    handle_reach: float  # how far a side handle stands off the body, or a top handle rises over the lid
    handle_thickness: float  # handle's half-thickness
    handle_skew: float  # where a side handle bulges out most, 0 = at the bottom, 1 = at the top
    lid_dome: float  # lid's dome height, fraction of the rim radius
    knob_radius: float  # knob radius, fraction of the rim radius
    body: Literal["round", "tall"]
    handle: Literal["side", "top"]
    lobes: int  # number of lobes of a melon body, 0 = smooth
    knob: Literal["ball", "flat"]


def sample_params(rng: np.random.Generator) -> TeapotParams:
    """Draw teapot parameters."""
    body = ("round", "tall")[rng.integers(2)]
    radius = rng.uniform(0.06, 0.1)
    height = radius * (rng.uniform(1.0, 1.5) if body == "round" else rng.uniform(1.5, 2.3))
    handle = ("side", "side", "top")[rng.integers(3)]
    return TeapotParams(
        radius=radius,
        height=height,
        widest=rng.uniform(0.3, 0.55),
        foot=rng.uniform(0.5, 0.8),
        rim=rng.uniform(0.4, 0.7),
        lobe_depth=rng.uniform(0.025, 0.06),
        spout_length=rng.uniform(0.75, 1.4),
        spout_tip=rng.uniform(0.72, 0.98),
        spout_angle=rng.uniform(np.radians(40), np.radians(68)),
        spout_bend=rng.uniform(-0.05, 0.15),
        spout_radius=rng.uniform(0.13, 0.22),
        spout_taper=rng.uniform(0.4, 0.75),
        handle_span=rng.uniform(0.45, 0.7) if handle == "side" else rng.uniform(0.6, 0.9),
        handle_reach=radius * rng.uniform(0.3, 0.55),
        handle_thickness=radius * rng.uniform(0.07, 0.12),
        handle_skew=rng.uniform(0.35, 0.75),
        lid_dome=rng.uniform(0.1, 0.45),
        knob_radius=rng.uniform(0.12, 0.25),
        body=body,
        handle=handle,
        lobes=0 if rng.uniform() < 0.65 else int(rng.integers(5, 11)),
        knob=("ball", "flat")[rng.integers(2)],
    )


def body_profile(p: TeapotParams, n: int = 48) -> np.ndarray:
    """(n, 2) (radius, z) outline of the body from its foot (z = 0) to the rim (z = height), z increasing."""
    r, h = p.radius, p.height
    zw = p.widest * h
    control = np.array(
        [
            [p.foot * r, 0.0],
            [(p.foot + 0.35 * (1.0 - p.foot)) * r, 0.35 * zw],
            [r, zw],
            [0.5 * (1.0 + p.rim) * r * 1.04, zw + 0.6 * (h - zw)],
            [p.rim * r, h],
        ]
    )
    curve = smooth_curve(control[:, ::-1], n)[:, ::-1]
    curve[:, 0] = np.clip(curve[:, 0], 0.3 * r, 1.08 * r)
    return curve


def radius_at(p: TeapotParams, z: float) -> float:
    """The smooth body's radius at height ``z`` (lobes aside)."""
    prof = body_profile(p)
    return float(np.interp(z, prof[:, 1], prof[:, 0]))


def _body(p: TeapotParams) -> trimesh.Trimesh:
    """The body: a surface of revolution, or a loft of lobed sections for a melon body."""
    prof = body_profile(p)
    if p.lobes == 0:
        return revolve(prof, segments=64)
    t = np.linspace(0.0, 2.0 * np.pi, 96, endpoint=False)
    wave = 1.0 + p.lobe_depth * (np.abs(np.cos(0.5 * p.lobes * t)) * 2.0 - 1.0)
    ring = np.stack([wave * np.cos(t), wave * np.sin(t)], 1)
    rings = [np.column_stack([ring * r, np.full(len(t), z)]) for r, z in prof]
    return loft(np.stack(rings))


def spout_path(p: TeapotParams, n: int = 40) -> np.ndarray:
    """(n, 3) centre line of the spout in the xz plane, from inside the body to the tip."""
    z_tip = p.spout_tip * p.height
    zb = max(0.25 * p.height, z_tip - p.spout_length * p.radius * np.sin(p.spout_angle))
    rb = radius_at(p, zb)
    exit_ = np.array([rb, 0.0, zb])
    rise = z_tip - zb
    length = rise / np.sin(p.spout_angle)
    direction = np.array([np.cos(p.spout_angle), 0.0, np.sin(p.spout_angle)])
    tip = exit_ + length * direction
    bow = np.array([np.sin(p.spout_angle), 0.0, -np.cos(p.spout_angle)])  # perpendicular, outward and down
    start = direction + [1.0, 0.0, 0.0]  # leaves the body between horizontal and the chord's direction
    start /= np.linalg.norm(start)
    control = np.array(
        [
            exit_ - 0.6 * rb * start,
            exit_,
            exit_ + 0.5 * length * direction + p.spout_bend * length * bow,
            tip,
        ]
    )
    return smooth_curve(control, n)


def _spout(p: TeapotParams) -> trimesh.Trimesh:
    """The spout: a tube along :func:`spout_path` that flares where it meets the body and tapers to the tip."""
    path = spout_path(p)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    s = arc / arc[-1]
    outside = np.hypot(path[:, 0], path[:, 1]) > np.interp(path[:, 2], *body_profile(p)[:, ::-1].T)
    s_exit = s[np.argmax(outside)]
    u = np.clip((s - s_exit) / (1.0 - s_exit), 0.0, 1.0)  # 0 at the body, 1 at the tip
    r0 = p.spout_radius * p.radius
    radius = r0 * (1.0 - (1.0 - p.spout_taper) * u) * (1.0 + 0.35 * np.exp(-u / 0.1))
    return tube(path, radius, sides=24)


def _side_handle_path(p: TeapotParams, n: int = 48) -> np.ndarray:
    """(n, 3) centre line of a side handle in the xz plane on the -x side, from top attachment to bottom."""
    h = p.height
    z_mid = h * (0.55 + 0.1 * p.widest)
    zu, zl = z_mid + 0.5 * p.handle_span * h, z_mid - 0.5 * p.handle_span * h
    zu = min(zu, 0.93 * h)
    ru, rl = radius_at(p, zu), radius_at(p, zl)
    far = p.radius + p.handle_reach
    z_far = zl + p.handle_skew * (zu - zl)
    control = np.array(
        [
            [-0.6 * ru, zu],
            [-(ru + 0.45 * (far - ru)), zu + 0.05 * h],
            [-far, z_far],
            [-(rl + 0.4 * (far - rl)), zl - 0.02 * h],
            [-0.6 * rl, zl],
        ]
    )
    curve = smooth_curve(control, n)
    return np.column_stack([curve[:, 0], np.zeros(n), curve[:, 1]])


def _top_handle_path(p: TeapotParams, n: int = 48) -> np.ndarray:
    """(n, 3) centre line of an arch over the lid in the xz plane, from the front attachment to the back."""
    za = p.height * (1.0 - 0.25 * p.handle_span)
    ra = radius_at(p, za)
    lid_top = p.height + p.lid_dome * p.rim * p.radius + 2.5 * p.knob_radius * p.rim * p.radius
    top = lid_top + p.handle_reach
    half = 0.85 * ra
    phi = np.linspace(0.0, np.pi, n)
    x = half * np.cos(phi) - 0.1 * half * np.sin(phi)  # leans slightly back towards -x
    z = za + (top - za) * np.sin(phi) ** 0.8
    sink = np.array([[0.85 * half, 0.0, za - 0.08 * p.height]])
    arch = np.column_stack([x, np.zeros(n), z])
    return np.concatenate([sink, arch[1:-1], sink * [-1.0, 1.0, 1.0]])


def _handle(p: TeapotParams) -> trimesh.Trimesh:
    """The handle: a flattened strap (an ellipse section, wide in y) along its centre line."""
    path = _side_handle_path(p) if p.handle == "side" else _top_handle_path(p)
    section = ellipse(0.7, 1.2, 24)
    return sweep(path, section, scales=p.handle_thickness)


def _lid(p: TeapotParams) -> trimesh.Trimesh:
    """The lid: a plug into the rim, a flange, a dome and a knob, as one surface of revolution."""
    rr = p.rim * p.radius
    h = p.height
    dome = p.lid_dome * rr
    k = p.knob_radius * rr
    t = np.linspace(0.0, 1.0, 14)
    dome_r = 1.06 * rr - t * (1.06 * rr - 0.45 * k)
    dome_z = h + 0.004 + dome * np.sin(0.5 * np.pi * t) ** 0.7
    points = [(0.9 * rr, h - 0.1 * rr), (0.9 * rr, h), (1.06 * rr, h)]
    points += list(zip(dome_r, dome_z, strict=True))
    zk = dome_z[-1] + 0.5 * k
    if p.knob == "ball":
        a = np.linspace(-0.6 * np.pi, 0.5 * np.pi, 12)
        points += [(0.45 * k, zk - 0.2 * k)] + list(zip(k * np.cos(a), zk + 0.8 * k + k * np.sin(a), strict=True))[1:]
    else:
        points += [(0.45 * k, zk), (1.2 * k, zk + 0.3 * k), (1.2 * k, zk + 0.6 * k), (0.0, zk + 0.6 * k)]
    return revolve(np.array(points), segments=48)


def build(p: TeapotParams, body: Material, handle: Material, lid: Material) -> ObjectAsset:
    """Build the teapot's parts from its parameters; the spout shares the body's material."""
    parts = [
        Part("body", "contain", _body(p), materials=(body,)),
        Part("spout", "pour", _spout(p), materials=(body,)),
        Part("handle", "grasp", _handle(p), materials=(handle,)),
        Part("lid", "open", _lid(p), materials=(lid,)),
    ]
    return ObjectAsset(category="teapot", parts=parts, params=asdict(p))


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random teapot: porcelain in any colour (sometimes patterned), handle and lid matching or contrasting."""
    params = sample_params(rng)
    body = random_material(rng, pattern_probability=0.3, period=(0.01, 0.04))
    handle = body if rng.uniform() < 0.6 else Material(color=random_color(rng, value=(0.15, 0.6)))
    lid = body if rng.uniform() < 0.8 else random_material(rng, pattern_probability=0.0)
    return build(params, body, handle, lid)
