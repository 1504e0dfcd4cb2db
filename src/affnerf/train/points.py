"""3D supervision points of a training object, made once from its ``mesh.ply`` (conventions §2, §4).

As Occupancy Networks, DISN and IF-Net sample their training points: a share uniform over the scene cube and the
rest near the surface (area-weighted surface samples moved by Gaussian noise of each given sigma), each with

- an **occupancy** target (1 inside the object), and
- an **affordance** target: the label of the nearest face for points inside or within :data:`LABEL_BAND` of the
  surface, 0 (no target; the field never predicts background) for the rest of free space, and
- a **signed distance** target: the distance to the surface, negative inside, truncated at :data:`DISTANCE_TRUNCATION`
  (DeepSDF's clamp; read only by fields whose geometry is a signed distance, ``--model.geometry sdf``).

Inside or outside: :func:`affnerf.solid.inside_mesh` (a majority of 5 ray tests; winding numbers on closed meshes,
so parts that interpenetrate are inside where they overlap).

With a part balance b > 0 (:func:`part_face_weights`), the near-surface samples weight each face by its area times
its affordance part's total area to the power -b: at b = 1 every part gets the same share of the points however
small its surface (a bucket's bail, a cabinet's handles), at b = 0 the plain area weighting.

The nearest face is that of the nearest of :data:`SURFACE_SAMPLES` area-weighted surface samples (about 1 mm apart
on a 0.44 m object) that lie on the object's outer boundary (:func:`affnerf.solid.outer_samples`: faces sunk into
another part are not its surface), so labels and distances are those of the surface the cameras see, exact up to
the sample spacing; points deeper inside than the band use every :data:`DEEP_STRIDE`-th sample (about 3 mm apart),
which only matters where two parts are nearly equidistant.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from affnerf.meshio import LabelledMesh
from affnerf.solid import inside_mesh, keep_outer

#: Points kept per object (N).
POINT_SET_SIZE = 65536
#: Share of the N points drawn uniformly over the scene cube; the rest are split evenly between the noise sigmas.
UNIFORM_SHARE = 0.25
#: Surface samples whose faces stand for the nearest face.
SURFACE_SAMPLES = 200_000
#: Points deeper inside than :data:`LABEL_BAND` take the label of the nearest of every DEEP_STRIDE-th sample.
DEEP_STRIDE = 8
#: Points outside the object farther than this from its surface (metres) get no affordance target.
LABEL_BAND = 0.01
#: Signed distances are kept up to this magnitude (metres); points farther from the surface hold +-this value.
DISTANCE_TRUNCATION = 0.05


@dataclass
class PointSet:
    """One object's supervision points.

    Attributes:
        points: (N, 3) float32 canonical positions inside the scene cube.
        occupancy: (N,) uint8, 1 inside the object.
        labels: (N,) uint8 affordance id of the nearest face; 0 = no affordance target.
        distance: (N,) float16 signed distance to the surface in metres (negative inside), clamped to
            +-:data:`DISTANCE_TRUNCATION`.
    """

    points: np.ndarray
    occupancy: np.ndarray
    labels: np.ndarray
    distance: np.ndarray

    def __len__(self) -> int:
        return len(self.points)


def split_counts(total: int, num_sigmas: int, uniform_share: float = UNIFORM_SHARE) -> list[int]:
    """How many of ``total`` points are uniform (first) and near the surface at each sigma (the rest).

    Example:
        >>> split_counts(65536, 2)
        [16384, 24576, 24576]
        >>> split_counts(10, 3, 0.5)
        [5, 2, 2, 1]
    """
    uniform = int(round(total * uniform_share)) if num_sigmas else total
    near = np.full(num_sigmas, (total - uniform) // max(num_sigmas, 1), dtype=int)
    near[: (total - uniform) - int(near.sum())] += 1
    return [uniform, *near.tolist()]


def part_face_weights(areas: np.ndarray, labels: np.ndarray, balance: float) -> np.ndarray:
    """(F,) sampling weight of each face: its area times its part's total area to the power ``-balance``.

    Args:
        areas: (F,) face areas; labels: (F,) the faces' part (affordance) ids; balance: b in [0, 1].

    Example:
        >>> labels = np.array([1, 1, 2, 2])
        >>> w = part_face_weights(np.array([3.0, 1.0, 0.5, 0.5]), labels, 1.0)
        >>> float(w[labels == 1].sum()), float(w[labels == 2].sum())
        (1.0, 1.0)
    """
    areas = np.asarray(areas, np.float64)
    _, part = np.unique(labels, return_inverse=True)
    part_area = np.bincount(part, weights=areas)
    return areas * np.maximum(part_area[part], 1e-12) ** (-float(balance))


def sample_positions(
    mesh: trimesh.Trimesh,
    half_extent: float,
    sigmas: tuple[float, ...],
    total: int,
    rng: np.random.Generator,
    face_weight: np.ndarray | None = None,
    uniform_share: float = UNIFORM_SHARE,
) -> np.ndarray:
    """(total, 3) positions: uniform over the cube [-half_extent, half_extent]^3, then surface samples (area-weighted,
    or by the (F,) ``face_weight``) plus isotropic Gaussian noise of each sigma (metres), clipped to the cube;
    ``uniform_share`` of them uniform (:func:`split_counts`)."""
    counts = split_counts(total, len(sigmas), uniform_share)
    parts = [rng.uniform(-half_extent, half_extent, (counts[0], 3))]
    for sigma, count in zip(sigmas, counts[1:], strict=True):
        surface, _ = trimesh.sample.sample_surface(mesh, count, face_weight=face_weight, seed=int(rng.integers(2**31)))
        parts.append(surface + rng.normal(0.0, sigma, (count, 3)))
    return np.clip(np.concatenate(parts), -half_extent, half_extent)


def surface_samples(mesh: trimesh.Trimesh, seed: int) -> tuple[cKDTree, np.ndarray]:
    """A k-d tree over the outer ones (:func:`~affnerf.solid.outer_samples`) of :data:`SURFACE_SAMPLES`
    area-weighted surface samples of ``mesh`` and the (S,) face of each: the samples stand for the faces in
    nearest-face and distance queries, so a point near a hidden face takes the label of, and its distance to, the
    surface a camera sees (all samples are kept where the test finds almost none outer: a mesh it cannot read)."""
    samples, faces = trimesh.sample.sample_surface(mesh, SURFACE_SAMPLES, seed=seed)
    samples, faces = keep_outer(mesh, samples, np.asarray(faces))
    return cKDTree(samples), faces


def nearest_labels(
    tree: cKDTree, sample_faces: np.ndarray, face_labels: np.ndarray, points: np.ndarray, inside: np.ndarray
) -> np.ndarray:
    """(N,) uint8 label of the face nearest to each point that is ``inside`` or within :data:`LABEL_BAND` of the
    surface, 0 elsewhere.

    Args:
        tree, sample_faces: :func:`surface_samples` of the mesh; face_labels: (F,) its faces' affordance ids;
        points: (N, 3); inside: (N,) bool.
    """
    dist, index = tree.query(points, distance_upper_bound=LABEL_BAND)
    near = np.isfinite(dist)
    labels = np.zeros(len(points), np.uint8)
    labels[near] = face_labels[sample_faces[index[near]]]
    deep = inside & ~near  # inside, but farther from the surface than the band: no early exit
    if deep.any():
        # Deep inside a round part, every surface sample is nearly equidistant and an exact k-d tree query visits
        # most of them; every DEEP_STRIDE-th sample answers which part a deep point belongs to ~10x faster.
        coarse = cKDTree(tree.data[::DEEP_STRIDE])
        labels[deep] = face_labels[sample_faces[::DEEP_STRIDE][coarse.query(points[deep])[1]]]
    return labels


def signed_distances(
    tree: cKDTree, points: np.ndarray, inside: np.ndarray, truncation: float = DISTANCE_TRUNCATION
) -> np.ndarray:
    """(N,) float16 distance of each (N, 3) point to the nearest surface sample of ``tree`` (about 1 mm apart, so
    exact to about that), negative ``inside``, clamped to +-``truncation``.

    Example:
        >>> tree = cKDTree(np.array([[0.0, 0.0, 0.0]]))
        >>> signed_distances(tree, np.array([[0.01, 0, 0], [0, 0.02, 0], [1.0, 0, 0]]), np.array([0, 1, 0]) > 0,
        ...                  0.05).astype(float).round(3).tolist()
        [0.01, -0.02, 0.05]
    """
    dist, _ = tree.query(points, distance_upper_bound=truncation)
    dist = np.minimum(dist, truncation)  # beyond the bound the query answers inf
    return np.where(inside, -dist, dist).astype(np.float16)


def make_point_set(
    mesh: LabelledMesh,
    half_extent: float,
    sigmas: tuple[float, ...],
    seed: int,
    total: int = POINT_SET_SIZE,
    part_balance: float = 0.0,
    uniform_share: float = UNIFORM_SHARE,
) -> PointSet:
    """The supervision points of a labelled mesh (face property ``affordance``), see the module docstring.

    Args:
        mesh: the object's ``mesh.ply`` in the canonical frame.
        half_extent: half the side of the scene cube (``ModelConfig.scene_half_extent``), metres.
        sigmas: noise sigmas of the near-surface points, metres.
        seed: seed of the draws (the same seed and mesh give the same points).
        total: N, points in the set.
        part_balance: b of the near-surface samples' part weighting (:func:`part_face_weights`; 0 = by area).
        uniform_share: the share of the points drawn uniformly over the cube (:func:`split_counts`).
    """
    if "affordance" not in mesh.face_props:
        raise ValueError("mesh has no per-face 'affordance' property")
    rng = np.random.default_rng([seed, 53])
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    face_labels = np.asarray(mesh.face_props["affordance"])
    weight = part_face_weights(tm.area_faces, face_labels, part_balance) if part_balance > 0 else None
    points = sample_positions(tm, half_extent, sigmas, total, rng, weight, uniform_share)
    inside = inside_mesh(tm, points)
    tree, sample_faces = surface_samples(tm, int(rng.integers(2**31)))
    labels = nearest_labels(tree, sample_faces, face_labels, points, inside)
    distance = signed_distances(tree, points, inside)
    return PointSet(points.astype(np.float32), inside.astype(np.uint8), labels, distance)
