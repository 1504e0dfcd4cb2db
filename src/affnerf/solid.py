"""Solids bounded by triangle meshes: which points are inside, and which surface samples lie on the outer surface.

Inside or outside (:func:`inside_mesh`): rays are cast from each point in :data:`RAY_DIRECTIONS` (5 fixed, not
axis-aligned), and the majority of the 5 answers is kept, so a ray that slips through a crack between faces, hits
an edge twice or escapes through a small hole is outvoted. For a closed, consistently oriented mesh (every
procedural object) each answer is the ray's signed crossing count (exits minus entries: the winding number), so
parts that interpenetrate (a handle sunk into a body) are inside where they overlap. Other meshes (PartNet-Mobility
meshes are often open or inconsistently oriented) use the parity of the crossings, which ignores face orientation;
there, a region enclosed twice by overlapping parts counts as outside, and open sheets enclose nothing.

An object built from parts has faces that no camera sees: those sunk into another part. :func:`outer_samples`
tells the samples of its outer surface from them; the 3D supervision (``train/points.py``) and the 3D metrics
(``eval/surface.py``) use only the outer ones.
"""

from __future__ import annotations

import numpy as np
import trimesh

#: Step (metres) to either side of a surface sample in the hidden-face test of :func:`outer_samples`.
HIDDEN_STEP = 3e-4
#: Below this share of outer samples the hidden-face test is taken for failed and every sample is kept.
MIN_OUTER_SHARE = 0.2


def _directions() -> np.ndarray:
    d = np.random.default_rng(7).normal(size=(5, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


#: (5, 3) unit directions of the inside test's rays (fixed, so a point set depends only on the mesh).
RAY_DIRECTIONS = _directions()


def _crossings(mesh: trimesh.Trimesh, points: np.ndarray, direction: np.ndarray, signed: bool) -> np.ndarray:
    """(N,) per point, the winding number (``signed``) or the number of faces the ray along ``direction`` crosses."""
    dirs = np.broadcast_to(direction, points.shape)
    tri, ray = mesh.ray.intersects_id(points, dirs, multiple_hits=True, return_locations=False)
    weights = np.sign(mesh.face_normals[tri] @ direction) if signed else np.ones(len(tri))
    return np.bincount(ray, weights=weights, minlength=len(points))


def inside_mesh(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    """(N,) bool: whether each (N, 3) point is inside ``mesh``, by a majority of 5 ray tests (see the module
    docstring: winding numbers on closed, consistently oriented meshes, crossing parity on others).

    Example:
        >>> box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
        >>> inside_mesh(box, np.array([[0.1, 0.2, 0.3], [0.6, 0.0, 0.0], [0.0, 0.0, -0.7]])).tolist()
        [True, False, False]
    """
    return _inside(*_solid(mesh), points)


def _solid(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, bool]:
    """``mesh`` with its duplicate vertices merged (so shared edges connect), and whether it is closed and
    consistently oriented (winding numbers apply) rather than read by crossing parity."""
    merged = trimesh.Trimesh(mesh.vertices, mesh.faces, process=True)
    return merged, bool(merged.is_watertight and merged.is_winding_consistent)


def _inside(merged: trimesh.Trimesh, signed: bool, points: np.ndarray) -> np.ndarray:
    """:func:`inside_mesh` on a mesh already prepared by :func:`_solid`."""
    votes = np.zeros(len(points), dtype=int)
    for direction in RAY_DIRECTIONS:
        count = _crossings(merged, points, direction, signed)
        votes += (count > 0.5) if signed else (np.rint(count).astype(int) % 2 == 1)
    return votes * 2 > len(RAY_DIRECTIONS)


def outer_samples(mesh: trimesh.Trimesh, samples: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(S,) bool: whether each (S, 3) surface sample of ``mesh`` (on the (S,) ``faces``) lies on the object's outer
    boundary, i.e. not both of the points :data:`HIDDEN_STEP` to either side of its face are inside the mesh
    (:func:`inside_mesh`). A face of one part sunk into another (a pen's barrel under its cap, a spout's root in a
    teapot's body, the overlap of two scissor blades) has solid on both sides: no camera sees it and it is not the
    object's surface. Testing both sides makes the answer independent of the faces' orientation.

    Example:
        >>> a, b = trimesh.creation.box(extents=(1, 1, 1)), trimesh.creation.box(extents=(0.5, 0.5, 0.5))
        >>> both = trimesh.util.concatenate([a, b])  # b sits wholly inside a
        >>> outer_samples(both, np.array([[0.5, 0.0, 0.0], [0.25, 0.0, 0.0]]), np.array([10, 22])).tolist()
        [True, False]
    """
    step = HIDDEN_STEP * mesh.face_normals[faces]
    solid = _solid(mesh)  # merged and ray-indexed once for both sides
    hidden = _inside(*solid, samples + step)
    if hidden.any():
        hidden[hidden] = _inside(*solid, samples[hidden] - step[hidden])
    return ~hidden


def keep_outer(mesh: trimesh.Trimesh, samples: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (S', 3) samples and (S',) faces of :func:`outer_samples` among (S, 3) ``samples`` on (S,) ``faces``;
    all of them where fewer than :data:`MIN_OUTER_SHARE` are outer (a mesh the inside test cannot read)."""
    outer = outer_samples(mesh, samples, faces) if len(samples) else np.zeros(0, bool)
    if len(samples) and outer.mean() >= MIN_OUTER_SHARE:
        return samples[outer], faces[outer]
    return samples, faces
