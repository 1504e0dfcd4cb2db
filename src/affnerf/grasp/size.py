"""The metric size of an object to grasp (conventions §6): dataset and predicted meshes are canonical (largest side
0.44 m); planning, epsilon and physics run at the object's real size, metric = canonical × ``factor``.

Where the size comes from, first that applies: ``--object-size`` (largest side in metres); the ``scale`` of the
``transforms.json`` beside a dataset mesh (canonical = source × scale, so factor = 1 / scale); the category's
typical size (:data:`CATEGORY_SIZE`); else the mesh is taken as it is, in metres. Masses come from the enclosed
volume times an effective density (:data:`CATEGORY_DENSITY`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from affnerf.errors import AffnerfError, input_error
from affnerf.fileio import read_json_file
from affnerf.grasp.target import GraspObject

#: Typical largest side in metres of an object of each category, for a model predicted from one photo.
CATEGORY_SIZE: dict[str, float] = {
    "screwdriver": 0.20,
    "pen": 0.14,
    "scissors": 0.18,
    "eyeglasses": 0.14,
    "bucket": 0.30,
    "bottle": 0.25,
    "teapot": 0.22,
    "cabinet": 0.80,
}
#: Effective density (kg/m^3): the typical mass over the volume the mesh encloses. Meshes model hollow or thin
#: objects as solids (a teapot or a cabinet), or thinner than steel blades are, so these are not material densities.
CATEGORY_DENSITY: dict[str, float] = {
    "screwdriver": 1200.0,  # plastic handle, steel shaft: ~0.1 kg
    "pen": 1200.0,  # ~0.012 kg
    "scissors": 4000.0,  # steel blades modelled thin: ~0.06 kg
    "eyeglasses": 3000.0,  # ~0.02-0.03 kg
    "bucket": 950.0,  # polypropylene walls: ~0.7 kg
    "bottle": 1000.0,  # full of water
    "teapot": 400.0,  # empty ceramic modelled solid: ~0.6-1 kg
    "cabinet": 400.0,  # panels: tens of kilograms
}
DEFAULT_DENSITY = 700.0  #: effective density of any other object (kg/m^3)
MIN_MASS = 0.005  #: masses are at least this (kg), for meshes that enclose almost nothing


@dataclass(frozen=True)
class ObjectSize:
    """How a canonical mesh becomes metric: metric = canonical × ``factor``.

    Attributes:
        factor: metres per canonical unit (1 / the dataset's ``scale``).
        source: where it came from (``--object-size``, ``transforms.json``, ``category <name>``, ``mesh as given``).
    """

    factor: float
    source: str

    @property
    def scale(self) -> float:
        """canonical = metric × scale (the dataset's ``scale`` for a dataset object).

        >>> ObjectSize(0.5, "x").scale
        2.0
        """
        return 1.0 / self.factor

    def to_json(self, canonical_extent: float) -> dict:
        """``{"scale", "largest_side" (metres), "source"}`` for ``grasps.json``."""
        return {"scale": self.scale, "largest_side": round(canonical_extent * self.factor, 6), "source": self.source}


def extent(vertices: np.ndarray) -> float:
    """Largest side of the axis-aligned bounding box of vertices (V, 3).

    >>> extent(np.array([[0.0, 0, 0], [0.4, 0.1, 0.2]]))
    0.4
    """
    return float(np.ptp(np.asarray(vertices, float), axis=0).max())


def size_for(
    canonical_extent: float,
    object_size: float | None = None,
    scale: float | None = None,
    category: str | None = None,
) -> ObjectSize:
    """The first size that applies (module docstring): ``object_size`` (largest side, m), ``scale``, the
    ``category``'s typical size, else 1 (the mesh as given).

    >>> size_for(0.44, category="pen").factor == 0.14 / 0.44
    True
    >>> size_for(0.44, scale=2.0).factor, size_for(0.44).source
    (0.5, 'mesh as given')
    """
    if object_size is not None:
        if not (np.isfinite(object_size) and object_size > 0):
            raise AffnerfError(f"--object-size must be a positive length in metres, got {object_size}")
        return ObjectSize(object_size / canonical_extent, "--object-size")
    if scale is not None:
        return ObjectSize(1.0 / scale, "transforms.json scale")
    if category is not None and category in CATEGORY_SIZE:
        return ObjectSize(CATEGORY_SIZE[category] / canonical_extent, f"category {category}")
    return ObjectSize(1.0, "mesh as given")


def dataset_scale(mesh_path: Path) -> tuple[float | None, str | None]:
    """``scale`` and ``category`` from the ``transforms.json`` beside a dataset mesh, (None, None) without one.

    Raises:
        AffnerfError: naming the file, when its ``scale`` is not a positive number.
    """
    path = Path(mesh_path).parent / "transforms.json"
    if not path.is_file():
        return None, None
    data = read_json_file(path)
    scale = data.get("scale") if isinstance(data, dict) else None
    if scale is not None and not (isinstance(scale, (int, float)) and np.isfinite(scale) and scale > 0):
        raise input_error(path, f"'scale' must be a positive number, got {scale!r}")
    category = data.get("category") if isinstance(data, dict) else None
    return (None if scale is None else float(scale)), (category if isinstance(category, str) else None)


def resolve_size(mesh_path: Path, vertices: np.ndarray, object_size: float | None, category: str | None) -> ObjectSize:
    """The size of the mesh at ``mesh_path`` with canonical ``vertices`` (V, 3): ``object_size``, then a
    ``transforms.json`` beside it, then ``category`` (given, or that file's), then the mesh as given."""
    scale, file_category = dataset_scale(mesh_path)
    return size_for(extent(vertices), object_size, scale, category or file_category)


def scaled(obj: GraspObject, factor: float) -> GraspObject:
    """The object with vertices (V, 3) multiplied by ``factor`` about the origin (labels, agreement, confidence and
    name kept)."""
    return GraspObject(
        obj.vertices * factor, obj.faces, obj.face_affordance, obj.name, obj.face_agrees, obj.face_confidence
    )


def rescale_poses(poses: np.ndarray, factor: float) -> np.ndarray:
    """Grasp poses (G, 4, 4) in a frame scaled by ``factor``: translations multiplied, rotations kept.

    >>> float(rescale_poses(np.eye(4)[None] + np.eye(4, k=3)[None], 0.5)[0, 0, 3])
    0.5
    """
    out = np.array(poses, dtype=float, copy=True)
    out[:, :3, 3] *= factor
    return out


def enclosed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume (m^3) a mesh (V, 3), (F, 3) encloses: the absolute signed volume of its triangles, which is exact
    for any union of closed, consistently wound pieces (overlaps count twice).

    >>> import trimesh
    >>> box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    >>> round(enclosed_volume(box.vertices, box.faces), 6)
    0.006
    """
    tri = np.asarray(vertices, float)[np.asarray(faces)]
    signed = np.einsum("fi,fi->f", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0
    return float(abs(signed))


def object_mass(vertices: np.ndarray, faces: np.ndarray, category: str | None = None) -> float:
    """Mass (kg) of a metric mesh: its enclosed volume times the category's effective density (at least
    :data:`MIN_MASS`).

    >>> import trimesh
    >>> box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    >>> round(object_mass(box.vertices, box.faces, "bottle"), 6)
    1.0
    """
    density = CATEGORY_DENSITY.get(category or "", DEFAULT_DENSITY)
    return max(MIN_MASS, density * enclosed_volume(vertices, faces))
