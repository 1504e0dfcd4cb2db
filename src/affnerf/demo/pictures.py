"""Pictures for reports: a labelled mesh coloured by affordance from a few sides, and the demo's overview sheet."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.data.cameras import Intrinsics, look_at
from affnerf.data.render import Renderer
from affnerf.meshio import LabelledMesh, majority_face_labels
from affnerf.objects.asset import Material, SurfaceMesh
from affnerf.viz import stack_rows, text_strip
from affnerf.vocab import AFFORDANCE_PALETTE


def mesh_preview(mesh: LabelledMesh, size: int = 240, yaws: tuple[float, ...] = (-115.0, 0.0, 115.0)) -> np.ndarray:
    """(size, len(yaws) * size, 3) uint8 renders of a mesh coloured by its affordance labels, on white."""
    if len(mesh.faces) == 0:
        return np.full((size, size * len(yaws), 3), 255, np.uint8)
    labels = mesh.face_props.get("affordance")
    if labels is None:
        labels = majority_face_labels(mesh.faces, np.asarray(mesh.vertex_props.get("affordance", np.zeros(len(mesh.vertices), int))))
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


def _fit(image: np.ndarray, height: int) -> np.ndarray:
    """Resize (keeping the aspect ratio) to ``height`` rows."""
    width = max(1, round(image.shape[1] * height / image.shape[0]))
    return np.asarray(Image.fromarray(image).convert("RGB").resize((width, height), Image.LANCZOS))


def overview_sheet(folders: Sequence[Path], height: int = 150) -> np.ndarray | None:
    """(H, W, 3) uint8: one row per demo example folder, input | a novel view (RGB | affordance) | the labelled
    mesh | the best grasps; folders without a mesh are left out (None when none has one)."""
    rows = []
    for folder in folders:
        folder = Path(folder)
        original = next(iter(sorted(folder.glob("original.*"))), None)
        turntable = sorted((folder / "turntable").glob("*.png"))
        if original is None or not turntable or not (folder / "mesh_preview.png").is_file():
            continue
        row = [_fit(np.asarray(Image.open(p)), height) for p in (original, turntable[len(turntable) // 6], folder / "mesh_preview.png")]
        if (folder / "grasps" / "grasps.png").is_file():
            row.append(_fit(np.asarray(Image.open(folder / "grasps" / "grasps.png")), height))
        rows.append(np.concatenate([np.pad(im, ((0, 0), (0, 4), (0, 0)), constant_values=255) for im in row], axis=1))
    if not rows:
        return None
    header = text_strip("input   |   novel view: colour | affordance   |   labelled mesh   |   grasps", rows[0].shape[1])
    return stack_rows([header, *[np.pad(r, ((0, 4), (0, 0), (0, 0)), constant_values=255) for r in rows]])
