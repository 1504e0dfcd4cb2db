"""Pictures of labelled meshes for reports: the mesh coloured by affordance, from a few sides."""

from __future__ import annotations

import numpy as np

from affnerf.data.cameras import Intrinsics, look_at
from affnerf.data.render import Renderer
from affnerf.meshio import LabelledMesh
from affnerf.objects.asset import Material, SurfaceMesh
from affnerf.predict.mesh import face_labels
from affnerf.vocab import AFFORDANCE_PALETTE


def mesh_preview(mesh: LabelledMesh, size: int = 240, yaws: tuple[float, ...] = (-115.0, 0.0, 115.0)) -> np.ndarray:
    """(size, len(yaws) * size, 3) uint8 renders of a mesh coloured by its affordance labels, on white."""
    if len(mesh.faces) == 0:
        return np.full((size, size * len(yaws), 3), 255, np.uint8)
    labels = mesh.face_props.get("affordance")
    if labels is None:
        labels = face_labels(mesh.faces, np.asarray(mesh.vertex_props.get("affordance", np.zeros(len(mesh.vertices), int))))
    labels = np.asarray(labels, np.int64)
    classes = np.unique(labels)
    materials = [Material(tuple(AFFORDANCE_PALETTE[c % len(AFFORDANCE_PALETTE)] / 255.0 * 0.8 + 0.15)) for c in classes]
    n = len(mesh.faces)
    surface = SurfaceMesh(
        vertices=np.asarray(mesh.vertices, np.float64), faces=np.asarray(mesh.faces, np.int64),
        face_part=np.ones(n, np.uint8), face_affordance=labels.astype(np.uint8),
        face_material=np.searchsorted(classes, labels).astype(np.int32), face_uv=np.zeros((n, 3, 2), np.float32),
        materials=materials,
    )  # fmt: skip
    renderer = Renderer(surface)
    intr = Intrinsics.from_fov(size, size, np.radians(50))
    centre = (mesh.vertices.min(0) + mesh.vertices.max(0)) / 2
    reach = float(np.ptp(mesh.vertices, axis=0).max()) * 1.5 + 0.05
    views = []
    for yaw in yaws:
        a = np.radians(yaw)
        eye = centre + reach * np.array([np.cos(a) * 0.8, np.sin(a) * 0.8, 0.55])
        views.append(renderer.render(intr, look_at(eye, centre)).rgb)
    return np.concatenate(views, axis=1)
