"""Labelled triangle meshes in PLY: vertices and faces with named integer properties and optional colours.

Used for the dataset's ground-truth ``mesh.ply`` (per-face and per-vertex ``part`` and ``affordance``) and for the
predicted affordance models (a vertex property ``affordance``). Any PLY reader sees an ordinary mesh; ours also
returns the extra properties.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from affnerf.errors import input_error
from affnerf.fileio import atomic_write


@dataclass
class LabelledMesh:
    """A triangle mesh with named per-vertex and per-face integer properties.

    Attributes:
        vertices: (V, 3) float positions.
        faces: (F, 3) int vertex indices.
        vertex_props: name -> (V,) integer array.
        face_props: name -> (F,) integer array.
        vertex_colors: (V, 3) uint8 RGB, or None.
    """

    vertices: np.ndarray
    faces: np.ndarray
    vertex_props: dict[str, np.ndarray] = field(default_factory=dict)
    face_props: dict[str, np.ndarray] = field(default_factory=dict)
    vertex_colors: np.ndarray | None = None

    def to_trimesh(self) -> trimesh.Trimesh:
        """A trimesh of the geometry (and colours), without the properties."""
        mesh = trimesh.Trimesh(self.vertices, self.faces, process=False)
        if self.vertex_colors is not None:
            mesh.visual.vertex_colors = np.asarray(self.vertex_colors, np.uint8)
        return mesh


def write_labelled_ply(path: Path, mesh: LabelledMesh) -> None:
    """Write a binary PLY with the mesh's properties, atomically (temporary file + rename)."""
    path = Path(path)
    tm = mesh.to_trimesh()
    for name, values in mesh.vertex_props.items():
        tm.vertex_attributes[name] = np.asarray(values)
    for name, values in mesh.face_props.items():
        tm.face_attributes[name] = np.asarray(values)
    data = tm.export(file_type="ply", encoding="binary")
    atomic_write(path, lambda f: f.write(data))


def majority_face_labels(faces: np.ndarray, vertex_labels: np.ndarray) -> np.ndarray:
    """(F,) label of each face from (V,) vertex labels: the one most of its vertices carry (the first vertex's
    when all three differ).

    Example:
        >>> majority_face_labels(np.array([[0, 1, 2]]), np.array([3, 5, 5])).tolist()
        [5]
    """
    a, b, c = (vertex_labels[faces[:, k]] for k in range(3))
    return np.where((b == c) & (a != b), b, a)


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,) area of each triangle of (V, 3) vertices and (F, 3) faces, in squared units of the vertices."""
    tri = np.asarray(vertices)[np.asarray(faces)]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def sample_surface_points(
    vertices: np.ndarray, faces: np.ndarray, count: int, rng: np.random.Generator, weights: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Random points uniform over a triangle mesh's area (each face's area times its ``weights`` entry, e.g. a 0/1
    mask), and the face each lies on.

    Args:
        vertices: (V, 3) positions.
        faces: (F, 3) vertex indices.
        count: points to draw.
        rng: the generator.
        weights: (F,) non-negative factors on the face areas, or None.

    Returns:
        points (count, 3) and their faces (count,); both empty when the weighted area is zero.

    Example:
        >>> tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> p, f = sample_surface_points(tri, np.array([[0, 1, 2]]), 50, np.random.default_rng(0))
        >>> bool((p[:, :2].sum(axis=1) <= 1).all() and (p[:, 2] == 0).all()), set(f.tolist())
        (True, {0})
    """
    vertices, faces = np.asarray(vertices, np.float64), np.asarray(faces, np.int64).reshape(-1, 3)
    area = face_areas(vertices, faces) if len(faces) else np.zeros(0)
    if weights is not None:
        area = area * weights
    total = float(area.sum())
    if count <= 0 or not total > 0:
        return np.zeros((0, 3)), np.zeros(0, np.int64)
    chosen = rng.choice(len(faces), count, p=area / total)
    r = rng.random((count, 2))
    flip = r.sum(1) > 1
    r[flip] = 1 - r[flip]
    tri = vertices[faces[chosen]]
    points = tri[:, 0] + r[:, :1] * (tri[:, 1] - tri[:, 0]) + r[:, 1:] * (tri[:, 2] - tri[:, 0])
    return points, chosen


_GEOMETRY_FIELDS = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "vertex_indices", "s", "t"}


def read_labelled_ply(path: Path) -> LabelledMesh:
    """Read a PLY mesh with its extra integer vertex and face properties.

    Raises:
        AffnerfError: for a missing or unreadable file, a mesh without faces, or non-finite vertices.
    """
    path = Path(path)
    if not path.is_file():
        raise input_error(path, "file not found")
    try:
        tm = trimesh.load(path, file_type="ply", process=False, force="mesh")
    except Exception as exc:  # trimesh raises many types for malformed files
        raise input_error(path, f"cannot read PLY mesh ({type(exc).__name__}: {exc})") from None
    if not isinstance(tm, trimesh.Trimesh) or len(tm.faces) == 0:
        raise input_error(path, "mesh has no faces")
    vertices = np.asarray(tm.vertices, np.float64)
    if not np.isfinite(vertices).all():
        raise input_error(path, "mesh has non-finite vertices")
    raw = tm.metadata.get("_ply_raw", {})
    props: dict[str, dict[str, np.ndarray]] = {"vertex": {}, "face": {}}
    for element in ("vertex", "face"):
        data = raw.get(element, {}).get("data")
        if data is None or data.dtype.names is None:
            continue
        for name in data.dtype.names:
            if name not in _GEOMETRY_FIELDS and np.issubdtype(data[name].dtype, np.number) and data[name].ndim == 1:
                props[element][name] = np.asarray(data[name])
    colors = None
    if tm.visual.kind == "vertex":
        colors = np.asarray(tm.visual.vertex_colors)[:, :3].astype(np.uint8)
    return LabelledMesh(vertices, np.asarray(tm.faces, np.int64), props["vertex"], props["face"], colors)
