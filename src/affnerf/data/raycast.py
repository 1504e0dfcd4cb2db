"""Ray casting of part-annotated meshes into dataset frames (colour, z-depth, affordance, part), with embreex.

The word for this in affnerf is *ray-cast*: *render* means volume rendering of a radiance field
(:mod:`affnerf.rendering`, :func:`affnerf.model.views.render_view`).

One ray per pixel through its centre (conventions §1), so colour, z-depth, affordance and part maps agree pixel for
pixel. Shading is ambient plus a light at the camera, on smooth normals that keep creases sharp; the albedo comes
from each face's material (plain colour, solid procedural pattern, or an image texture sampled at the UV).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

from affnerf.data.cameras import Intrinsics, world_rays
from affnerf.objects.asset import Material, SurfaceMesh


@dataclass(frozen=True)
class Frame:
    """One rendered view.

    Attributes:
        rgb: (H, W, 3) uint8; background pixels are exactly the background colour.
        depth: (H, W) float32 z-depth in metres, 0 where no surface.
        affordance: (H, W) uint8 affordance ids, 0 background.
        part: (H, W) uint8 part ids, 0 background.
    """

    rgb: np.ndarray
    depth: np.ndarray
    affordance: np.ndarray
    part: np.ndarray


@dataclass(frozen=True)
class Lighting:
    """Shading constants: ``ambient + diffuse * |cos|`` of the angle between normal and view ray."""

    ambient: float = 0.35
    diffuse: float = 0.65
    crease_angle_deg: float = 35.0


def corner_normals(vertices: np.ndarray, faces: np.ndarray, crease_angle_deg: float) -> np.ndarray:
    """Smooth shading normals per face corner that do not smooth across creases.

    Each corner averages (area-weighted) the normals of the faces around its vertex that lie within
    ``crease_angle_deg`` of its own face's normal.

    Args:
        vertices: (V, 3) positions.
        faces: (F, 3) indices.
        crease_angle_deg: faces meeting at a larger angle keep separate normals.

    Returns:
        (F, 3, 3) unit normals, one per corner.
    """
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1, keepdims=True)
    face_n = cross / np.maximum(area2, 1e-20)
    # incidence entries (one per face corner), grouped by vertex
    order = np.argsort(faces.reshape(-1), kind="stable")
    vert_sorted = faces.reshape(-1)[order]
    face_sorted = order // 3
    counts = np.bincount(vert_sorted, minlength=len(vertices))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    # every (corner, neighbouring face) pair around the same vertex
    group = counts[vert_sorted]
    a = np.repeat(np.arange(len(order)), group)
    offsets = np.arange(len(a)) - np.repeat(np.cumsum(group) - group, group)
    b = starts[vert_sorted[a]] + offsets
    fa, fb = face_sorted[a], face_sorted[b]
    keep = np.einsum("pk,pk->p", face_n[fa], face_n[fb]) >= np.cos(np.radians(crease_angle_deg))
    weighted = face_n * area2
    summed = np.zeros((len(order), 3))
    for c in range(3):
        summed[:, c] = np.bincount(a[keep], weights=weighted[fb[keep], c], minlength=len(order))
    norm = np.linalg.norm(summed, axis=1, keepdims=True)
    normals_sorted = np.where(norm > 1e-20, summed / np.maximum(norm, 1e-20), face_n[face_sorted])
    out = np.empty((len(order), 3))
    out[order] = normals_sorted
    return out.reshape(len(faces), 3, 3)


def _pattern_weight(material: Material, points: np.ndarray) -> np.ndarray:
    """(N,) weight of ``color2`` of a solid procedural pattern at object-frame ``points`` (N, 3)."""
    half = material.period / 2.0
    if material.pattern == "stripes":
        return (np.floor(points @ np.asarray(material.axis) / half) % 2).astype(np.float64)
    if material.pattern == "checker":
        return (np.floor(points / half).astype(np.int64).sum(axis=1) % 2).astype(np.float64)
    if material.pattern == "speckle":
        cells = np.floor(points / material.period).astype(np.int64)
        h = (cells * np.array([73856093, 19349663, 83492791])).sum(axis=1) % 1024
        return (h / 1023.0) ** 2
    return np.zeros(len(points))


def sample_texture(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear lookup of an (H, W, 3) uint8 image at UVs (N, 2), wrapping; v = 0 is the image's bottom row.

    Returns:
        (N, 3) float colours in [0, 1].
    """
    h, w = image.shape[:2]
    x = (uv[:, 0] % 1.0) * w - 0.5
    y = (1.0 - (uv[:, 1] % 1.0)) * h - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    img = image.astype(np.float64) / 255.0

    def at(yy: np.ndarray, xx: np.ndarray) -> np.ndarray:
        return img[yy % h, xx % w]

    top = at(y0, x0) * (1 - fx) + at(y0, x0 + 1) * fx
    bottom = at(y0 + 1, x0) * (1 - fx) + at(y0 + 1, x0 + 1) * fx
    return top * (1 - fy) + bottom * fy


def albedo(surface: SurfaceMesh, face: np.ndarray, points: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """(N, 3) surface colour at hit ``points`` (N, 3) on faces ``face`` (N,) with barycentrics ``bary`` (N, 3)."""
    out = np.empty((len(face), 3))
    mat_of = surface.face_material[face]
    for m in np.unique(mat_of):
        sel = mat_of == m
        material = surface.materials[m]
        color = np.broadcast_to(np.asarray(material.color, np.float64), (int(sel.sum()), 3))
        if material.texture is not None:
            uv = np.einsum("nk,nkc->nc", bary[sel], surface.face_uv[face[sel]].astype(np.float64))
            color = color * sample_texture(material.texture, uv)
        if material.pattern != "plain":
            w = _pattern_weight(material, points[sel])[:, None]
            color = color * (1 - w) + np.asarray(material.color2) * w
        out[sel] = color
    return out


class RayCaster:
    """First hits of rays on a triangle mesh (Embree).

    Args:
        vertices: (V, 3) positions.
        faces: (F, 3) vertex indices.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self._scene = rtcore_scene.EmbreeScene()
        TriangleMesh(
            scene=self._scene,
            vertices=np.ascontiguousarray(vertices, np.float32),
            indices=np.ascontiguousarray(faces, np.int32),
        )

    def cast(self, origins: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """First hits of rays.

        Args:
            origins: (N, 3) ray origins.
            dirs: (N, 3) ray directions (any length: the returned ``t`` is in units of it).

        Returns:
            ray indices that hit (M,), their faces (M,), the ray parameters t (M,) and barycentrics (M, 3) of the
            hit points in their faces' corner order.
        """
        out = self._scene.run(
            np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(dirs, np.float32), output=1
        )
        ray = np.flatnonzero(out["geomID"] != -1)
        u, v = out["u"][ray].astype(np.float64), out["v"][ray].astype(np.float64)
        bary = np.stack([1.0 - u - v, u, v], 1)
        return ray, out["primID"][ray].astype(np.int64), out["tfar"][ray].astype(np.float64), bary


class FrameCaster:
    """Ray-casts one object's frames from any camera: colour, z-depth, affordance and part maps.

    Example:
        >>> from affnerf.objects.registry import make_object
        >>> from affnerf.objects.asset import merge_parts
        >>> from affnerf.data.cameras import Intrinsics, look_at
        >>> r = FrameCaster(merge_parts(make_object("screwdriver", 0)))
        >>> f = r.cast_frame(Intrinsics.from_fov(40, 30, 1.0), look_at(np.array([0.0, -0.6, 0.3]), np.zeros(3)))
        >>> f.rgb.shape, bool((f.part > 0).any())
        ((30, 40, 3), True)
    """

    def __init__(
        self,
        surface: SurfaceMesh,
        background: tuple[float, float, float] = (1.0, 1.0, 1.0),
        lighting: Lighting = Lighting(),
    ) -> None:
        self.surface = surface
        self.background = np.asarray(background, np.float64)
        self.lighting = lighting
        self.caster = RayCaster(surface.vertices, surface.faces)
        self._corner_normals = corner_normals(surface.vertices, surface.faces, lighting.crease_angle_deg)

    def cast(self, origins: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """First hits of rays on the object (see :meth:`RayCaster.cast`)."""
        return self.caster.cast(origins, dirs)

    def cast_frame(self, intr: Intrinsics, c2w: np.ndarray) -> Frame:
        """Ray-cast the four maps of one camera frame from camera-to-world pose ``c2w`` (4, 4)."""
        origins, dirs = world_rays(intr, c2w)
        # each direction has unit length along the camera's -z axis, so a hit's t is its z-depth
        ray, face, z, bary = self.cast(origins, dirs)
        h, w = intr.height, intr.width
        rgb = np.broadcast_to(self.background, (h * w, 3)).copy()
        depth = np.zeros(h * w, np.float32)
        aff = np.zeros(h * w, np.uint8)
        part = np.zeros(h * w, np.uint8)
        if len(face):
            points = origins[ray] + z[:, None] * dirs[ray]
            normals = np.einsum("nk,nkc->nc", bary, self._corner_normals[face])
            normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
            unit = dirs[ray] / np.linalg.norm(dirs[ray], axis=1, keepdims=True)
            cos = np.abs(np.einsum("nc,nc->n", normals, unit))
            light = self.lighting.ambient + self.lighting.diffuse * cos
            rgb[ray] = albedo(self.surface, face, points, bary) * light[:, None]
            depth[ray] = z
            aff[ray] = self.surface.face_affordance[face]
            part[ray] = self.surface.face_part[face]
        rgb8 = np.clip(np.round(rgb * 255.0), 0, 255).astype(np.uint8)
        return Frame(rgb8.reshape(h, w, 3), depth.reshape(h, w), aff.reshape(h, w), part.reshape(h, w))
