"""Pictures of meshes: any mesh with per-face colours ray-cast from a few sides around it, and a labelled mesh
coloured by affordance."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from affnerf.data.cameras import Intrinsics, look_at
from affnerf.data.raycast import FrameCaster
from affnerf.meshio import LabelledMesh, majority_face_labels
from affnerf.objects.asset import Material, SurfaceMesh
from affnerf.vocab import AFFORDANCE_PALETTE


def coloured_surface(vertices: np.ndarray, faces: np.ndarray, face_colors: np.ndarray) -> SurfaceMesh:
    """A surface that the ray caster shades with one flat colour per face.

    Args:
        vertices: (V, 3) positions.
        faces: (F, 3) vertex indices.
        face_colors: (F, 3) RGB in [0, 1].
    """
    colors, material = np.unique(np.round(np.asarray(face_colors, np.float64), 3), axis=0, return_inverse=True)
    n = len(faces)
    return SurfaceMesh(
        vertices=np.asarray(vertices, np.float64),
        faces=np.asarray(faces, np.int64),
        face_part=np.ones(n, np.uint8),
        face_affordance=np.zeros(n, np.uint8),
        face_material=material.reshape(-1).astype(np.int32),
        face_uv=np.zeros((n, 3, 2), np.float32),
        materials=[Material(tuple(c)) for c in colors],
    )


def views_around(
    surface: SurfaceMesh,
    centre: np.ndarray,
    reach: float,
    yaws: Sequence[float],
    size: int,
    lift: float = 0.55,
) -> np.ndarray:
    """(size, len(yaws) * size, 3) uint8: the surface seen from cameras at ``reach`` from ``centre``, one per yaw
    (degrees about +z), each raised by ``lift`` times the reach and looking at the centre, side by side."""
    caster = FrameCaster(surface)
    intr = Intrinsics.from_fov(size, size, np.radians(50))
    views = []
    for yaw in yaws:
        a = np.radians(yaw)
        eye = centre + reach * np.array([np.cos(a) * 0.8, np.sin(a) * 0.8, lift])
        views.append(caster.cast_frame(intr, look_at(eye, centre)).rgb)
    return np.concatenate(views, axis=1)


def affordance_colors(labels: np.ndarray, strength: float = 0.8, floor: float = 0.15) -> np.ndarray:
    """(F, 3) RGB in [0, 1] of affordance ids, softened (``strength`` of the palette colour plus ``floor``) so
    shading stays visible on dark classes."""
    labels = np.asarray(labels, np.int64)
    return AFFORDANCE_PALETTE[labels % len(AFFORDANCE_PALETTE)] / 255.0 * strength + floor


def mesh_preview(mesh: LabelledMesh, size: int = 240, yaws: tuple[float, ...] = (-115.0, 0.0, 115.0)) -> np.ndarray:
    """(size, len(yaws) * size, 3) uint8 pictures of a mesh coloured by its affordance labels, on white."""
    if len(mesh.faces) == 0:
        return np.full((size, size * len(yaws), 3), 255, np.uint8)
    labels = mesh.face_props.get("affordance")
    if labels is None:
        vertex_labels = mesh.vertex_props.get("affordance", np.zeros(len(mesh.vertices), int))
        labels = majority_face_labels(mesh.faces, np.asarray(vertex_labels))
    surface = coloured_surface(mesh.vertices, mesh.faces, affordance_colors(labels))
    centre = (mesh.vertices.min(0) + mesh.vertices.max(0)) / 2
    reach = float(np.ptp(mesh.vertices, axis=0).max()) * 1.5 + 0.05
    return views_around(surface, centre, reach, yaws, size)
