"""Labelled meshes from fields: marching cubes on density in the model's scene cube, each vertex labelled by the
field's affordance there and coloured by its class.

The functions take plain callables (points -> density, points -> class ids), so they work on a trained model
(``model.point_fields``) as well as on analytic fields in tests.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import torch
from skimage import measure

from affnerf.meshio import LabelledMesh, face_areas, majority_face_labels
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import POINTS_PER_CHUNK
from affnerf.predict.level import object_level
from affnerf.rendering.grid import OccupancyGrid
from affnerf.vocab import colorize_labels

PointFn = Callable[[torch.Tensor], torch.Tensor]


def grid_axis(resolution: int, half_extent: float) -> np.ndarray:
    """(resolution,) coordinates of grid samples along one axis, from -half_extent to +half_extent inclusive."""
    return np.linspace(-half_extent, half_extent, resolution)


def grid_spacing(resolution: int, half_extent: float) -> float:
    """Distance between neighbouring samples of :func:`grid_axis`.

    Example:
        >>> grid_spacing(5, 1.0)
        0.5
    """
    return 2.0 * half_extent / (resolution - 1)


@torch.no_grad()
def evaluate_grid(
    fn: PointFn,
    resolution: int,
    half_extent: float,
    chunk: int = POINTS_PER_CHUNK,
    occupancy: OccupancyGrid | None = None,
) -> np.ndarray:
    """Evaluate a scalar field on a cubic grid.

    Args:
        fn: (N, 3) float32 points -> (N,) values.
        resolution: samples per axis.
        half_extent: the grid spans [-half_extent, half_extent]^3.
        chunk: points per call.
        occupancy: evaluate only at points in its occupied cells; the others get 0 (empty space skipping).

    Returns:
        (R, R, R) float32 values indexed [x, y, z].
    """
    axis = torch.from_numpy(grid_axis(resolution, half_extent)).float()
    out = np.zeros(resolution**3, np.float32)
    xs, ys, zs = torch.meshgrid(axis, axis, axis, indexing="ij")
    points = torch.stack([xs.reshape(-1), ys.reshape(-1), zs.reshape(-1)], dim=-1)
    index = torch.arange(len(points))
    if occupancy is not None:
        index = index[occupancy.lookup(points)]
    for start in range(0, len(index), chunk):
        sel = index[start : start + chunk]
        out[sel.numpy()] = fn(points[sel]).float().cpu().numpy()
    return out.reshape(resolution, resolution, resolution)


def marching_cubes(volume: np.ndarray, level: float, half_extent: float) -> tuple[np.ndarray, np.ndarray]:
    """The ``level`` isosurface of a grid of density, with normals pointing out of the dense region.

    Args:
        volume: (R, R, R) values indexed [x, y, z] over [-half_extent, half_extent]^3.
        level: the surface's value.
        half_extent: the grid's half side.

    Returns:
        vertices (V, 3) in the canonical frame and faces (F, 3); both empty when the level is never crossed.
    """
    if not (volume.min() < level < volume.max()):
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    res = volume.shape[0]
    spacing = 2.0 * half_extent / (res - 1)
    verts, faces, _, _ = measure.marching_cubes(volume, level, spacing=(spacing,) * 3, gradient_direction="ascent")
    return verts - half_extent, faces.astype(np.int64)


@torch.no_grad()
def evaluate_points(fn: PointFn, points: np.ndarray, chunk: int = POINTS_PER_CHUNK) -> np.ndarray:
    """(N, ...) values of ``fn`` at (N, 3) points, in chunks."""
    out = [fn(torch.from_numpy(points[s : s + chunk]).float()).cpu().numpy() for s in range(0, len(points), chunk)]
    return np.concatenate(out) if out else np.zeros(0)


def labelled_mesh_from_grid(
    volume: np.ndarray, labels: PointFn, level: float, half_extent: float, chunk: int = POINTS_PER_CHUNK
) -> LabelledMesh:
    """Marching cubes at ``level`` on an already evaluated density grid, each vertex labelled by ``labels``.

    Args:
        volume: (R, R, R) density indexed [x, y, z] over [-half_extent, half_extent]^3 (:func:`evaluate_grid`).
        labels: (N, 3) float32 points -> (N,) class ids.
        level: density of the surface.
        half_extent: the grid's half side.
        chunk: points per call of ``labels``.

    Returns:
        A :class:`LabelledMesh` with the vertex property ``affordance``, the face property ``affordance`` and
        vertex colours of the classes (no faces if the density never reaches ``level``).
    """
    vertices, faces = marching_cubes(volume, level, half_extent)
    vertex_labels = (
        evaluate_points(labels, vertices, chunk).astype(np.int64) if len(vertices) else np.zeros(0, np.int64)
    )
    return LabelledMesh(
        vertices=vertices,
        faces=faces,
        vertex_props={"affordance": vertex_labels.astype(np.uint8)},
        face_props={"affordance": majority_face_labels(faces, vertex_labels).astype(np.uint8)},
        vertex_colors=colorize_labels(vertex_labels),
    )


def face_confidence(mesh: LabelledMesh, probabilities: PointFn, chunk: int = POINTS_PER_CHUNK) -> np.ndarray:
    """(F,) uint8 how sure the field is of each face's ``affordance`` label: the probability of that label among
    the object classes at the face's centre, in whole percent rounded down (so ``>= 80`` is ``p >= 0.80``).

    Args:
        mesh: a labelled mesh with the face property ``affordance`` (class ids from 1).
        probabilities: (N, 3) float32 points -> (N, C - 1) probabilities of the object classes 1..C-1
            (``model.point_probabilities``).
        chunk: points per call.

    Example:
        >>> m = LabelledMesh(np.eye(3), np.array([[0, 1, 2]]), face_props={"affordance": np.array([2])})
        >>> face_confidence(m, lambda p: torch.tensor([[0.25, 0.75]]).expand(len(p), 2)).tolist()
        [75]
    """
    labels = np.asarray(mesh.face_props["affordance"], np.int64)
    if not len(labels):
        return np.zeros(0, np.uint8)
    centres = np.asarray(mesh.vertices, np.float32)[mesh.faces].mean(axis=1)
    p = evaluate_points(probabilities, centres, chunk)
    chosen = p[np.arange(len(labels)), np.clip(labels - 1, 0, p.shape[1] - 1)]
    return np.floor(np.clip(chosen, 0.0, 1.0) * 100.0 + 1e-6).astype(np.uint8)


def label_faces(vertices: np.ndarray, faces: np.ndarray, labels: PointFn, chunk: int = POINTS_PER_CHUNK) -> np.ndarray:
    """(F,) int64 class ids a field gives at the centres of a mesh's faces: a mesh from elsewhere (the true mesh
    of a dataset object, a scan) labelled by a predicted affordance field, in the field's frame.

    Args:
        vertices: (V, 3); faces: (F, 3).
        labels: (N, 3) float32 points -> (N,) class ids (``model.point_fields(encoding)[1]``).
        chunk: points per call.

    Example:
        >>> tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -3]])
        >>> label_faces(tri, np.array([[0, 1, 2], [0, 1, 3]]), lambda p: 1 + (p[:, 2] < 0).long()).tolist()
        [1, 2]
    """
    if not len(faces):
        return np.zeros(0, np.int64)
    centres = np.asarray(vertices, np.float32)[np.asarray(faces)].mean(axis=1)
    return evaluate_points(labels, centres, chunk).astype(np.int64)


def extract_labelled_mesh(
    density: PointFn,
    labels: PointFn,
    resolution: int,
    level: float,
    half_extent: float,
    chunk: int = POINTS_PER_CHUNK,
    occupancy: OccupancyGrid | None = None,
) -> LabelledMesh:
    """Marching cubes on ``density`` with vertex and face affordance labels from ``labels`` (density evaluated
    only in the occupied cells of ``occupancy`` when given): :func:`evaluate_grid`, then
    :func:`labelled_mesh_from_grid`.

    Returns:
        A :class:`LabelledMesh` with the vertex property ``affordance``, the face property ``affordance`` and
        vertex colours of the classes (no faces if the density never reaches ``level``).
    """
    volume = evaluate_grid(density, resolution, half_extent, chunk, occupancy)
    return labelled_mesh_from_grid(volume, labels, level, half_extent, chunk)


def model_level(model: ConditionedNeRF, volume: np.ndarray) -> float:
    """The density level of one object's mesh from its (R, R, R) density grid over the model's scene cube
    (:func:`evaluate_grid`): the model's ``surface_density``, lowered for a diffuse object
    (:func:`affnerf.predict.level.object_level` with the model's ``surface_optical_depth``)."""
    config = model.config
    spacing = grid_spacing(volume.shape[0], config.scene_half_extent)
    return object_level(volume, spacing, config.surface_density, config.surface_optical_depth)


def model_surface(
    model: ConditionedNeRF,
    encoding: object,
    resolution: int = 128,
    level: float | None = None,
    occupancy: OccupancyGrid | None = None,
) -> tuple[LabelledMesh, float]:
    """The labelled mesh of one encoded object in the model's scene cube, and the density level it was cut at.
    Its faces carry ``affordance`` and ``confidence`` (:func:`face_confidence`).

    Args:
        model: a trained model.
        encoding: one object's encoding (``model.encode_views`` / ``model.encode``).
        resolution: marching-cubes samples per axis.
        level: density of the surface; None takes the object's own level from the model config
            (:func:`affnerf.predict.level.object_level`: ``surface_density``, lowered for a diffuse object when
            ``surface_optical_depth`` is set).
        occupancy: the object's occupancy grid (empty-space skipping), or None to evaluate everywhere.
    """
    density, labels = model.point_fields(encoding)
    half = model.config.scene_half_extent
    volume = evaluate_grid(density, resolution, half, occupancy=occupancy)
    if level is None:
        level = model_level(model, volume)
    mesh = labelled_mesh_from_grid(volume, labels, level, half)
    confidence = face_confidence(mesh, model.point_probabilities(encoding))
    return replace(mesh, face_props={**mesh.face_props, "confidence": confidence}), float(level)


def model_mesh(
    model: ConditionedNeRF,
    encoding: object,
    resolution: int = 128,
    level: float | None = None,
    occupancy: OccupancyGrid | None = None,
) -> LabelledMesh:
    """The labelled mesh of :func:`model_surface` without its level."""
    return model_surface(model, encoding, resolution, level, occupancy)[0]


def class_areas(mesh: LabelledMesh) -> dict[int, float]:
    """Surface area (m^2) per face affordance class."""
    area = face_areas(mesh.vertices, mesh.faces)
    labels = mesh.face_props["affordance"]
    return {int(c): float(area[labels == c].sum()) for c in np.unique(labels)}
