"""Closed, consistently oriented surfaces to build parts from.

Every builder returns a watertight :class:`trimesh.Trimesh` with outward normals (positive volume): surfaces of
revolution, sweeps of a cross-section along a path, extruded polygons, boxes and ellipsoids; and the 2D curves
that feed them (smooth splines, ellipses, superellipses).
"""

from __future__ import annotations

import numpy as np
import shapely.geometry
import trimesh
from scipy.interpolate import CubicSpline

_EPS = 1e-9


def _outward(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Flip a closed mesh's faces when its signed volume is negative, so normals point outward."""
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _make(vertices: np.ndarray, faces: np.ndarray) -> trimesh.Trimesh:
    mesh = trimesh.Trimesh(vertices=np.asarray(vertices, np.float64), faces=np.asarray(faces, np.int64), process=False)
    return _outward(mesh)


def _ring_faces(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quads, as two triangles each, between two index rings of equal length (M,) -> (2M, 3)."""
    a2, b2 = np.roll(a, -1), np.roll(b, -1)
    return np.concatenate([np.stack([a, a2, b2], 1), np.stack([a, b2, b], 1)])


def _fan_faces(centre: int, ring: np.ndarray) -> np.ndarray:
    """Triangles from one vertex to each edge of an index ring (M,) -> (M, 3)."""
    return np.stack([np.full_like(ring, centre), np.roll(ring, -1), ring], 1)


def revolve(
    profile: np.ndarray,
    segments: int = 48,
    closed: bool = False,
    scale_xy: tuple[float, float] = (1.0, 1.0),
) -> trimesh.Trimesh:
    """Revolve a profile of (radius, z) points about the z axis.

    Args:
        profile: (N, 2) points (r, z), r >= 0, in order along the outline. An open profile is closed onto the
            axis at both ends (a flat cap where an end has r > 0). With ``closed=True`` the profile is a loop
            that stays off the axis (a ring, like a bottle's lip or a torus).
        segments: number of angular steps.
        closed: whether ``profile`` is a closed loop.
        scale_xy: stretch of the x and y coordinates, for oval cross-sections.

    Returns:
        A watertight mesh. A cup is an open profile from the axis at the bottom, out, up the outer wall, down
        the inner wall and back to the axis at the inner floor.

    Example:
        >>> revolve(np.array([[0.1, 0.0], [0.1, 0.2]])).is_watertight  # a cylinder
        True
    """
    pts = np.asarray(profile, np.float64)
    if not closed:
        if pts[0, 0] > _EPS:
            pts = np.vstack([[0.0, pts[0, 1]], pts])
        if pts[-1, 0] > _EPS:
            pts = np.vstack([pts, [0.0, pts[-1, 1]]])
    elif np.any(pts[:, 0] <= _EPS):
        raise ValueError("a closed revolve profile must stay off the axis")
    theta = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    cos, sin = np.cos(theta) * scale_xy[0], np.sin(theta) * scale_xy[1]
    vertices, rings = [], []
    count = 0
    for r, z in pts:
        if r <= _EPS:
            vertices.append([[0.0, 0.0, z]])
            rings.append(count)
            count += 1
        else:
            vertices.append(np.stack([r * cos, r * sin, np.full(segments, z)], 1))
            rings.append(np.arange(count, count + segments))
            count += segments
    n = len(pts)
    pairs = [(i, i + 1) for i in range(n - 1)] + ([(n - 1, 0)] if closed else [])
    faces = []
    for i, j in pairs:
        a, b = rings[i], rings[j]
        if isinstance(a, int) and isinstance(b, int):
            continue
        if isinstance(a, int):
            faces.append(_fan_faces(a, b))
        elif isinstance(b, int):
            faces.append(_fan_faces(b, a)[:, [0, 2, 1]])
        else:
            faces.append(_ring_faces(a, b))
    return _make(np.concatenate(vertices), np.concatenate(faces))


def _rotation_minimising_frames(path: np.ndarray, closed: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tangents, normals and binormals (each (N, 3)) along a polyline by the double-reflection method."""
    n = len(path)
    if closed:
        tangents = np.roll(path, -1, 0) - np.roll(path, 1, 0)
    else:
        tangents = np.gradient(path, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    helper = np.array([0.0, 0.0, 1.0]) if abs(tangents[0, 2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    normals = np.zeros_like(path)
    normals[0] = np.cross(tangents[0], np.cross(helper, tangents[0]))
    normals[0] /= np.linalg.norm(normals[0])
    for i in range(n - 1):
        v1 = path[i + 1] - path[i]
        c1 = v1 @ v1
        r_l = normals[i] - (2.0 / c1) * (v1 @ normals[i]) * v1
        t_l = tangents[i] - (2.0 / c1) * (v1 @ tangents[i]) * v1
        v2 = tangents[i + 1] - t_l
        c2 = v2 @ v2
        normals[i + 1] = r_l - (2.0 / c2) * (v2 @ r_l) * v2 if c2 > _EPS else r_l
        normals[i + 1] /= np.linalg.norm(normals[i + 1])
    binormals = np.cross(tangents, normals)
    if closed:  # spread the frame's mismatch after one loop evenly, so the seam closes without a twist
        end_n = normals[-1]
        start_n = normals[0]
        angle = np.arctan2(np.dot(np.cross(end_n, start_n), tangents[0]), np.dot(end_n, start_n))
        phis = angle * np.arange(n) / n
        normals, binormals = (
            np.cos(phis)[:, None] * normals + np.sin(phis)[:, None] * binormals,
            -np.sin(phis)[:, None] * normals + np.cos(phis)[:, None] * binormals,
        )
    return tangents, normals, binormals


def sweep(
    path: np.ndarray,
    section: np.ndarray,
    scales: np.ndarray | float = 1.0,
    closed: bool = False,
) -> trimesh.Trimesh:
    """Sweep a 2D cross-section along a 3D path.

    Args:
        path: (N, 3) points; consecutive points must differ.
        section: (M, 2) closed polygon around its origin (star-shaped about it), in the plane normal to the path.
        scales: scale of the section at each path point, a float, (N,) or (N, 2) per section axis.
        closed: whether the path is a loop (no end caps) or open (flat caps at both ends).

    Returns:
        A watertight mesh.

    Example:
        >>> sweep(np.array([[0, 0, 0], [0, 0, 0.1]]), circle(0.01, 12)).is_watertight
        True
    """
    path = np.asarray(path, np.float64)
    section = np.asarray(section, np.float64)
    n, m = len(path), len(section)
    scales = np.broadcast_to(np.asarray(scales, np.float64).reshape(-1, 1) if np.ndim(scales) == 1 else scales, (n, 2))
    _, normals, binormals = _rotation_minimising_frames(path, closed)
    sx = section[None, :, 0] * scales[:, 0:1]
    sy = section[None, :, 1] * scales[:, 1:2]
    rings = path[:, None, :] + sx[..., None] * normals[:, None, :] + sy[..., None] * binormals[:, None, :]
    vertices = [rings.reshape(-1, 3)]
    idx = np.arange(n * m).reshape(n, m)
    faces = [_ring_faces(idx[i], idx[i + 1]) for i in range(n - 1)]
    if closed:
        faces.append(_ring_faces(idx[-1], idx[0]))
    else:
        vertices.append(path[[0, -1]])
        start, end = n * m, n * m + 1
        faces.append(_fan_faces(start, idx[0]))
        faces.append(_fan_faces(end, idx[-1])[:, [0, 2, 1]])
    return _make(np.concatenate(vertices), np.concatenate(faces))


def tube(path: np.ndarray, radius: np.ndarray | float, sides: int = 16, closed: bool = False) -> trimesh.Trimesh:
    """A round tube of (per-point) ``radius`` along ``path``; see :func:`sweep`."""
    return sweep(path, circle(1.0, sides), scales=radius, closed=closed)


def extrude(polygon: np.ndarray, height: float, holes: list[np.ndarray] | tuple = ()) -> trimesh.Trimesh:
    """Extrude a simple 2D polygon (with optional holes) along +z from z = 0 to z = ``height``.

    Args:
        polygon: (N, 2) outline, either orientation.
        height: thickness in metres (> 0).
        holes: (K, 2) outlines of holes inside ``polygon``.

    Returns:
        A watertight mesh.
    """
    shape = shapely.geometry.Polygon(np.asarray(polygon), [np.asarray(h) for h in holes])
    if not shape.is_valid:
        shape = shape.buffer(0)
    mesh = trimesh.creation.extrude_polygon(shape, height)
    mesh.merge_vertices()
    return _outward(mesh)


def box(extents: tuple[float, float, float] | np.ndarray) -> trimesh.Trimesh:
    """An axis-aligned box centred at the origin."""
    return _outward(trimesh.creation.box(extents=np.asarray(extents, np.float64)))


def ellipsoid(radii: tuple[float, float, float] | np.ndarray, subdivisions: int = 3) -> trimesh.Trimesh:
    """An ellipsoid centred at the origin (a scaled icosphere)."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    mesh.vertices = mesh.vertices * np.asarray(radii, np.float64)
    return _outward(mesh)


def cylinder(radius: float, height: float, sections: int = 32) -> trimesh.Trimesh:
    """A z-aligned cylinder from z = 0 to z = ``height``."""
    return revolve(np.array([[radius, 0.0], [radius, height]]), segments=sections)


def circle(radius: float, n: int = 24) -> np.ndarray:
    """(n, 2) counter-clockwise points on a circle."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return radius * np.stack([np.cos(t), np.sin(t)], 1)


def ellipse(a: float, b: float, n: int = 32) -> np.ndarray:
    """(n, 2) counter-clockwise points on an axis-aligned ellipse with half-axes ``a`` (x) and ``b`` (y)."""
    return circle(1.0, n) * np.array([a, b])


def superellipse(a: float, b: float, exponent: float, n: int = 48) -> np.ndarray:
    """(n, 2) points on |x/a|^e + |y/b|^e = 1: e = 2 is an ellipse, larger e tends to a rounded rectangle."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    c, s = np.cos(t), np.sin(t)
    x = a * np.sign(c) * np.abs(c) ** (2.0 / exponent)
    y = b * np.sign(s) * np.abs(s) ** (2.0 / exponent)
    return np.stack([x, y], 1)


def smooth_curve(control: np.ndarray, n: int, closed: bool = False) -> np.ndarray:
    """Sample a cubic spline through control points, parametrised by chord length.

    Args:
        control: (K, D) control points (K >= 2; a closed curve does not repeat its first point).
        n: number of output points.
        closed: whether the curve is periodic.

    Returns:
        (n, D) points; an open curve starts and ends at the first and last control points.
    """
    pts = np.asarray(control, np.float64)
    if closed:
        pts = np.vstack([pts, pts[:1]])
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    t = np.concatenate([[0.0], np.cumsum(seg)])
    if len(pts) == 2:
        s = np.linspace(0.0, 1.0, n)[:, None]
        return pts[0] * (1 - s) + pts[1] * s
    spline = CubicSpline(t, pts, bc_type="periodic" if closed else "natural")
    u = np.linspace(0.0, t[-1], n, endpoint=not closed)
    return spline(u)


def rotation(axis: tuple[float, float, float] | np.ndarray, angle: float) -> np.ndarray:
    """(4, 4) rotation by ``angle`` radians about ``axis`` through the origin."""
    return trimesh.transformations.rotation_matrix(angle, np.asarray(axis, np.float64))


def translation(offset: tuple[float, float, float] | np.ndarray) -> np.ndarray:
    """(4, 4) translation by ``offset``."""
    return trimesh.transformations.translation_matrix(np.asarray(offset, np.float64))


def align_z(direction: np.ndarray) -> np.ndarray:
    """(4, 4) rotation taking +z onto ``direction``."""
    d = np.asarray(direction, np.float64)
    return trimesh.geometry.align_vectors(np.array([0.0, 0.0, 1.0]), d / np.linalg.norm(d))


def placed(mesh: trimesh.Trimesh, *matrices: np.ndarray) -> trimesh.Trimesh:
    """A copy of ``mesh`` transformed by ``matrices`` applied left to right (the first is applied first)."""
    out = mesh.copy()
    for m in matrices:
        out.apply_transform(m)
    return out
