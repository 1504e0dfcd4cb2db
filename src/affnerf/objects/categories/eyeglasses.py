"""Eyeglasses: rims and a bridge (grasp), two temples (wear) and two lenses (view).

Canonical orientation: the front of the glasses stands in the xz plane facing -y (the lenses' normals along -y),
+z up, the bridge at x = 0, the right lens (as worn, seen from behind) at +x, and the temples running back toward
+y with the ear hooks bending down at their ends.

Shape parameters: lens width, lens height, lens shape exponent (superellipse: round to square), nasal droop of
the lens's lower inner corner, rim width, frame depth, bridge width, bridge arch, hinge height, temple length,
ear-bend start and angle, temple splay (open angle), wrap (face-form angle of each eye). Styles: round or square
lenses; full rims or half rims (top only); acetate (thick flat plastic) or wire frame (thin round metal);
clear lenses or sunglasses.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import shapely.geometry as geo
import trimesh

from affnerf.objects.appearance import metal, random_color, random_material
from affnerf.objects.asset import Material, ObjectAsset, Part
from affnerf.objects.primitives import (
    box,
    circle,
    extrude,
    placed,
    rotation,
    smooth_curve,
    superellipse,
    sweep,
    translation,
)

#: Takes an extrusion in the xy plane along +z to the front plane: 2D y becomes z (up), the extrusion runs along -y.
_TO_FRONT = rotation((1.0, 0.0, 0.0), np.pi / 2)
#: Mirror across the yz plane (right eye to left eye).
_MIRROR_X = np.diag([-1.0, 1.0, 1.0, 1.0])


@dataclass(frozen=True)
class EyeglassesParams:
    """Shape parameters of a pair of glasses (metres, radians)."""

    lens_width: float
    lens_height: float
    lens_exponent: float  # superellipse exponent of the lens outline: 2 = ellipse, larger = squarer
    lens_droop: float  # narrowing of the lens's lower nasal corner (aviator-like), 0 = none
    rim_width: float  # band width of an acetate rim, or wire radius of a wire rim
    frame_depth: float  # front-to-back thickness of an acetate rim
    bridge_width: float  # gap between the lenses
    bridge_arch: float  # rise of the bridge's middle above its ends
    hinge_height: float  # height of the hinges relative to the lens's half-height
    temple_length: float
    bend_start: float  # share of the temple before the ear bend
    bend_angle: float  # how far the ear hook turns down
    temple_splay: float  # outward turn of each temple from straight back (the open angle)
    wrap: float  # backward turn of each eye about its nasal edge (face form)
    lenses: Literal["round", "square"]
    rims: Literal["full", "half"]
    frame: Literal["acetate", "wire"]
    tint: Literal["clear", "sunglasses"]


def sample_params(rng: np.random.Generator) -> EyeglassesParams:
    """Draw eyeglasses parameters."""
    lenses = ("round", "square")[rng.integers(2)]
    frame = ("acetate", "wire")[rng.integers(2)]
    lens_width = rng.uniform(0.042, 0.058)
    return EyeglassesParams(
        lens_width=lens_width,
        lens_height=rng.uniform(0.55, 0.92) * lens_width,
        lens_exponent=rng.uniform(2.0, 2.6) if lenses == "round" else rng.uniform(3.0, 5.0),
        lens_droop=rng.uniform(0.0, 0.3) if rng.uniform() < 0.5 else 0.0,
        rim_width=rng.uniform(0.0025, 0.006) if frame == "acetate" else rng.uniform(0.0006, 0.0011),
        frame_depth=rng.uniform(0.003, 0.006),
        bridge_width=rng.uniform(0.014, 0.022),
        bridge_arch=rng.uniform(0.0, 0.007),
        hinge_height=rng.uniform(0.15, 0.6),
        temple_length=rng.uniform(0.125, 0.15),
        bend_start=rng.uniform(0.7, 0.82),
        bend_angle=rng.uniform(0.35, 0.9),
        temple_splay=rng.uniform(-0.04, 0.2),
        wrap=rng.uniform(0.0, 0.12),
        lenses=lenses,
        rims=("full", "half")[rng.choice(2, p=(0.75, 0.25))],
        frame=frame,
        tint=("clear", "sunglasses")[rng.choice(2, p=(0.65, 0.35))],
    )


def _lens_outline(p: EyeglassesParams, n: int = 96) -> np.ndarray:
    """(n, 2) counter-clockwise outline (x, z) of the right lens about its centre, starting at the bottom.

    The nasal side is -x; with droop, its lower part is pulled toward the centre.
    """
    a, b = 0.5 * p.lens_width, 0.5 * p.lens_height
    t = np.linspace(-0.5 * np.pi, 1.5 * np.pi, n, endpoint=False)
    c, s = np.cos(t), np.sin(t)
    x = a * np.sign(c) * np.abs(c) ** (2.0 / p.lens_exponent)
    z = b * np.sign(s) * np.abs(s) ** (2.0 / p.lens_exponent)
    x = np.where((x < 0) & (z < 0), x * (1.0 + p.lens_droop * z / b), x)
    return np.stack([x, z], 1)


def _lens_centre_x(p: EyeglassesParams) -> float:
    """x of the right lens's centre (its nasal edge is at half the bridge width)."""
    return 0.5 * p.bridge_width + 0.5 * p.lens_width


def _edge_x(shape: geo.Polygon, z: float, side: str) -> float:
    """x where a horizontal line at height z leaves a 2D shape (x, z), on its ``side`` ('min' or 'max')."""
    cut = shape.intersection(geo.LineString([(-1.0, z), (1.0, z)]))
    xs = np.asarray(cut.bounds)[[0, 2]]
    return float(xs[0] if side == "min" else xs[1])


def _slab(shape: geo.Polygon, depth: float) -> trimesh.Trimesh:
    """A 2D shape in the front plane (x, z) extruded front to back over y in [-depth/2, depth/2]."""
    shape = shape.simplify(1e-5)  # drops near-duplicate vertices that would collapse when the mesh is merged
    outline = np.asarray(shape.exterior.coords)[:-1]
    holes = [np.asarray(r.coords)[:-1] for r in shape.interiors]
    return placed(extrude(outline, depth, holes), _TO_FRONT, translation((0.0, 0.5 * depth, 0.0)))


def _in_front_plane(xz: np.ndarray) -> np.ndarray:
    """(N, 3) points at y = 0 from (N, 2) front-plane points (x, z)."""
    return np.stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]], 1)


def _rim(p: EyeglassesParams, lens: geo.Polygon, outline: np.ndarray) -> trimesh.Trimesh:
    """The right rim around ``lens``: a flat acetate band or a round wire, all round or only along the top."""
    cut_z = -0.1 * 0.5 * p.lens_height
    if p.frame == "acetate":
        band = lens.buffer(p.rim_width, 32).difference(lens.buffer(-0.0008, 32))
        if p.rims == "half":
            band = band.intersection(geo.box(-1.0, cut_z, 1.0, 1.0))
        return _slab(band, p.frame_depth)
    normals = np.roll(outline, -1, 0) - np.roll(outline, 1, 0)
    normals = np.stack([normals[:, 1], -normals[:, 0]], 1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    path = outline + 0.6 * p.rim_width * normals
    if p.rims == "full":
        return sweep(_in_front_plane(path), circle(p.rim_width, 12), closed=True)
    upper = path[path[:, 1] > cut_z]  # contiguous: the outline starts at the bottom
    return sweep(_in_front_plane(upper), circle(p.rim_width, 12))


def _hinge(p: EyeglassesParams, rim_shape: geo.Polygon) -> tuple[trimesh.Trimesh, np.ndarray]:
    """The end piece on the right rim's outer side, and the point (3,) behind it where the temple hinges."""
    z = p.hinge_height * 0.5 * p.lens_height
    x_out = _edge_x(rim_shape, z, "max")
    depth = p.frame_depth if p.frame == "acetate" else 0.002
    size = np.array([0.004, depth + 0.005, _temple_height(p) if p.frame == "acetate" else 0.003])
    centre = np.array([x_out + 0.5 * size[0] - 0.0015, 0.5 * size[1] - 0.5 * depth, z])
    hinge = centre + np.array([0.0, 0.5 * size[1] - 0.001, 0.0])
    return placed(box(size), translation(centre)), hinge


def _temple_height(p: EyeglassesParams) -> float:
    """Height of an acetate temple at its hinge, following the rim's width."""
    return 0.0035 + 0.6 * p.rim_width


def _temple_path(p: EyeglassesParams, n: int = 60) -> np.ndarray:
    """(n, 3) centre line of the right temple from its hinge (origin) back along +y, bending down behind the ear."""
    straight = p.bend_start * p.temple_length
    droop = 0.06
    radius = (1.0 - p.bend_start) * p.temple_length / p.bend_angle
    n1 = n // 2
    s = np.linspace(0.0, straight, n1, endpoint=False)
    line = np.stack([s * np.cos(droop), -s * np.sin(droop)], 1)
    phi = np.linspace(0.0, p.bend_angle, n - n1)
    start = np.array([straight * np.cos(droop), -straight * np.sin(droop)])
    centre = start + radius * np.array([-np.sin(droop), -np.cos(droop)])
    arc = centre + radius * np.stack([np.sin(droop + phi), np.cos(droop + phi)], 1)
    yz = np.vstack([line, arc])
    return np.stack([np.zeros(n), yz[:, 0], yz[:, 1]], 1)


def _temple(p: EyeglassesParams, hinge: np.ndarray) -> tuple[trimesh.Trimesh, np.ndarray]:
    """The right temple placed at ``hinge`` and splayed; also (F,) 1 for the ear-tip faces of a wire temple."""
    path = _temple_path(p)
    u = np.linspace(0.0, 1.0, len(path))
    if p.frame == "acetate":
        height = _temple_height(p)
        scales = np.stack([height * (1.0 - 0.5 * u), 0.0028 * (1.0 - 0.2 * u)], 1)
    else:
        tip = np.clip((u - p.bend_start + 0.05) / 0.05, 0.0, 1.0)
        scales = np.stack([0.0025 + 0.0017 * tip, 0.0014 + 0.0016 * tip], 1)
    mesh = sweep(path, superellipse(0.5, 0.5, 3.0, 20), scales=scales)
    ear = (mesh.triangles_center[:, 1] > 0.95 * p.bend_start * p.temple_length).astype(np.int64)
    return placed(mesh, rotation((0.0, 0.0, 1.0), -p.temple_splay), translation(hinge)), ear


def _bridge(p: EyeglassesParams, lens: geo.Polygon) -> trimesh.Trimesh:
    """The bridge between the rims' nasal sides, arching up in the middle."""
    z = 0.3 * 0.5 * p.lens_height
    x_end = _edge_x(lens, z, "min") - 0.3 * p.rim_width if p.frame == "wire" else _edge_x(lens, z, "min") + 0.001
    control = np.array([[-x_end, z], [0.0, z + p.bridge_arch], [x_end, z]])
    path = _in_front_plane(smooth_curve(control, 24))
    if p.frame == "wire":
        return sweep(path, circle(1.1 * p.rim_width, 12))
    return sweep(path, superellipse(0.5, 0.5, 4.0, 24), scales=np.array([[0.0045, p.frame_depth * 0.9]]).repeat(24, 0))


def _wrap(p: EyeglassesParams) -> np.ndarray:
    """(4, 4) turn of the right eye about the vertical line through its nasal edge."""
    x0 = 0.5 * p.bridge_width
    return translation((x0, 0.0, 0.0)) @ rotation((0.0, 0.0, 1.0), p.wrap) @ translation((-x0, 0.0, 0.0))


def _mirrored(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The mesh mirrored across the yz plane, with its faces flipped back to point outward."""
    out = placed(mesh, _MIRROR_X)
    if out.volume < 0:
        out.invert()
    return out


def _ear_tip_color(material: Material) -> tuple[float, float, float]:
    """A dark plastic colour for a wire temple's ear tip, tinted by the temple's colour."""
    return tuple(float(0.25 * c + 0.05) for c in material.color)  # type: ignore[return-value]


def build(p: EyeglassesParams, frame_mat: Material, temple_mat: Material, lens_mat: Material) -> ObjectAsset:
    """Build the glasses' parts from its parameters."""
    outline = _lens_outline(p) + np.array([_lens_centre_x(p), 0.0])
    lens_shape = geo.Polygon(outline)
    rim = _rim(p, lens_shape, outline)
    end_piece, hinge = _hinge(p, lens_shape.buffer(p.rim_width if p.frame == "acetate" else 1.2 * p.rim_width))
    temple, ear = _temple(p, hinge)
    wrap = _wrap(p)
    right = {
        "rim": placed(trimesh.util.concatenate([rim, end_piece]), wrap),
        "lens": placed(_slab(lens_shape, 0.0018), wrap),
        "temple": placed(temple, wrap),
    }
    temple_mats = (temple_mat,) if p.frame == "acetate" else (temple_mat, Material(color=_ear_tip_color(temple_mat)))
    temple_faces = None if p.frame == "acetate" else ear
    parts = [Part("bridge", "grasp", _bridge(p, lens_shape), (frame_mat,))]
    for side, mirror in (("left", _mirrored), ("right", lambda m: m)):
        parts += [
            Part(f"rim_{side}", "grasp", mirror(right["rim"]), (frame_mat,)),
            Part(f"lens_{side}", "view", mirror(right["lens"]), (lens_mat,)),
            Part(f"temple_{side}", "wear", mirror(right["temple"]), temple_mats, face_material=temple_faces),
        ]
    return ObjectAsset(category="eyeglasses", parts=parts, params=asdict(p))


def generate(rng: np.random.Generator) -> ObjectAsset:
    """A random pair of glasses."""
    params = sample_params(rng)
    if params.frame == "acetate":
        frame = random_material(rng, pattern_probability=0.3, period=(0.003, 0.012))
    else:
        frame = metal(rng) if rng.uniform() < 0.6 else Material(color=random_color(rng, value=(0.2, 0.8)))
    temple = frame if rng.uniform() < 0.75 else Material(color=random_color(rng))
    if params.tint == "clear":
        lens = Material(color=random_color(rng, saturation=(0.0, 0.12), value=(0.82, 0.97)))
    else:
        lens = Material(color=random_color(rng, saturation=(0.1, 0.6), value=(0.05, 0.3)))
    return build(params, frame, temple, lens)
