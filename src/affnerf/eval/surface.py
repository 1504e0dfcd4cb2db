"""The 3D side of the protocol (conventions §5): a method's labelled mesh of an object scored against the object's
true ``mesh.ply`` with :mod:`affnerf.metrics.surface`, and per-object scores gathered per category.

A method gives meshes through an optional capability, ``mesh(obj, inputs) -> LabelledMesh | None`` (see
:class:`MeshMethod`); a method without it, or one that returns None, has no 3D numbers (``null``), never zeros. An
empty mesh (no surface predicted) is scored: F = 0, mIoU = 0, Chamfer ``None``, counted in ``meshes_empty``.
"""

from __future__ import annotations

import math
import zlib
from typing import Any, Protocol

import numpy as np
import trimesh

from affnerf.data.dataset import ObjectData
from affnerf.meshio import LabelledMesh, read_labelled_ply, sample_surface_points
from affnerf.metrics.surface import (
    SURFACE_KEYS,
    SURFACE_SAMPLES,
    SurfaceSamples,
    empty_samples,
    surface_metrics,
)
from affnerf.solid import keep_outer

#: Per-object 3D scores: the :data:`~affnerf.metrics.surface.SURFACE_KEYS` values, or None for no mesh.
SurfaceScore = dict[str, float | None]


class MeshMethod(Protocol):
    """A method that also gives the labelled mesh it predicts from an object's input views (canonical frame,
    face property ``affordance``), or None when it has none for them."""

    def mesh(self, obj: ObjectData, inputs: list[int]) -> LabelledMesh | None: ...


def method_mesh(method: object, obj: ObjectData, inputs: list[int]) -> LabelledMesh | None:
    """The method's mesh of ``obj`` from ``inputs``; None for a method without the ``mesh`` capability."""
    mesh = getattr(method, "mesh", None)
    return None if mesh is None else mesh(obj, inputs)


def sample_seed(seed: int, object_id: str) -> list[int]:
    """The seed of an object's surface samples (the protocol's seed and the object, as for the view choice).

    Example:
        >>> sample_seed(0, "pen_0001") == sample_seed(0, "pen_0001") != sample_seed(1, "pen_0001")
        True
    """
    return [seed, zlib.crc32(object_id.encode())]


def mesh_samples(mesh: LabelledMesh, seed: list[int]) -> SurfaceSamples:
    """Area-weighted samples of a labelled mesh's outer surface (:func:`affnerf.solid.keep_outer`: samples on faces
    sunk into another part, which no camera sees, are dropped); faces without an ``affordance`` property count as
    background."""
    labels = np.asarray(mesh.face_props.get("affordance", np.zeros(len(mesh.faces), np.int64)), np.int64)
    points, faces = sample_surface_points(mesh.vertices, mesh.faces, SURFACE_SAMPLES, np.random.default_rng(seed))
    if not len(points):
        return empty_samples()
    points, faces = keep_outer(trimesh.Trimesh(mesh.vertices, mesh.faces, process=False), points, faces)
    return SurfaceSamples(points, labels[faces])


def true_samples(obj: ObjectData, seed: int) -> SurfaceSamples:
    """Samples of the object's ground-truth ``mesh.ply`` (face property ``affordance``)."""
    return mesh_samples(read_labelled_ply(obj.folder / "mesh.ply"), sample_seed(seed, obj.record.object_id) + [1])


def score_mesh(mesh: LabelledMesh | None, truth: SurfaceSamples, seed: list[int]) -> SurfaceScore | None:
    """The 3D metrics of a predicted mesh against the true samples; None when there is no mesh."""
    return None if mesh is None else surface_metrics(mesh_samples(mesh, seed), truth)


def _mean(values: list[Any]) -> float | None:
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.mean(finite)) if finite else None


def category_surface(scores: list[SurfaceScore | None]) -> dict[str, Any]:
    """A category's 3D metrics: each the mean over its objects' meshes (Chamfer over the non-empty ones), and
    ``meshes_empty`` counting empty ones; all None when no object has a mesh.

    Example:
        >>> s = [{"chamfer_l1": 0.02, "fscore_1cm": 0.5, "affordance_miou_3d": 0.4},
        ...      {"chamfer_l1": None, "fscore_1cm": 0.0, "affordance_miou_3d": 0.0}]
        >>> category_surface(s)
        {'chamfer_l1': 0.02, 'fscore_1cm': 0.25, 'affordance_miou_3d': 0.2, 'meshes_empty': 1}
        >>> category_surface([None])["fscore_1cm"] is None
        True
    """
    scored = [s for s in scores if s is not None]
    out: dict[str, Any] = {key: _mean([s[key] for s in scored]) for key in SURFACE_KEYS}
    out["meshes_empty"] = sum(s["chamfer_l1"] is None for s in scored) if scored else None
    return out


def mean_surface(categories: list[dict[str, Any]]) -> dict[str, Any]:
    """The 3D metrics averaged over categories where they are finite, and ``meshes_empty`` summed (None where
    no category has meshes)."""
    out: dict[str, Any] = {key: _mean([c.get(key) for c in categories]) for key in SURFACE_KEYS}
    empty = [c["meshes_empty"] for c in categories if c.get("meshes_empty") is not None]
    out["meshes_empty"] = sum(empty) if empty else None
    return out
