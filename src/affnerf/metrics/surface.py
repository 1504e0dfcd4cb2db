"""3D metrics of a predicted labelled mesh against the true one (conventions §5), in canonical metres.

Both meshes are compared through area-weighted samples of their surfaces (20,000 per mesh by default), each
sample carrying the affordance label of its face:

- **Chamfer-L1**: the mean of the two directed mean nearest-point distances (prediction → truth, truth →
  prediction).
- **F-score at τ** (1 cm): the harmonic mean of precision (share of predicted points within τ of a true point) and
  recall (share of true points within τ of a predicted point).
- **3D affordance mIoU**: each true point takes the label of its nearest predicted point; IoU per affordance class
  present in the truth (background excluded), then averaged.

An empty prediction (no faces, or no area) scores F = 0 and mIoU = 0; its Chamfer distance is ``None`` (written
``null``: JSON has no infinity), so averages of Chamfer run over the non-empty predictions only and the empty ones
are counted beside them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from affnerf.meshio import sample_surface_points

#: Surface samples per mesh.
SURFACE_SAMPLES = 20_000
#: The F-score's distance threshold τ, metres.
FSCORE_TAU = 0.01
#: The 3D metric keys, as written in ``metrics_<method>.json``.
SURFACE_KEYS = ("chamfer_l1", "fscore_1cm", "affordance_miou_3d")


@dataclass(frozen=True)
class SurfaceSamples:
    """Points on a surface and their labels.

    Attributes:
        points: (N, 3) float64 positions, metres.
        labels: (N,) int64 affordance ids of the faces they lie on.
    """

    points: np.ndarray
    labels: np.ndarray

    def __len__(self) -> int:
        return len(self.points)


def empty_samples() -> SurfaceSamples:
    """No points (the samples of an empty mesh)."""
    return SurfaceSamples(np.zeros((0, 3)), np.zeros(0, np.int64))


def sample_surface(
    vertices: np.ndarray,
    faces: np.ndarray,
    face_labels: np.ndarray,
    count: int = SURFACE_SAMPLES,
    rng: np.random.Generator | int = 0,
) -> SurfaceSamples:
    """Area-weighted uniform samples of a triangle mesh, each with its face's label.

    Args:
        vertices: (V, 3) positions.
        faces: (F, 3) vertex indices.
        face_labels: (F,) integer labels.
        count: samples to draw.
        rng: a generator, or the seed of one.

    Returns:
        ``count`` samples; none when the mesh has no faces or no area.

    Example:
        >>> tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> s = sample_surface(tri, np.array([[0, 1, 2]]), np.array([3]), count=100)
        >>> bool((s.points[:, :2].sum(axis=1) <= 1).all()), bool((s.points[:, 2] == 0).all()), set(s.labels.tolist())
        (True, True, {3})
    """
    points, chosen = sample_surface_points(vertices, faces, count, np.random.default_rng(rng))
    if not len(points):
        return empty_samples()
    return SurfaceSamples(points, np.asarray(face_labels, np.int64)[chosen])


def nearest(query: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance from each (N, 3) query point to its nearest (M, 3) reference point, and that point's index.

    Example:
        >>> d, i = nearest(np.array([[0.0, 0, 1]]), np.array([[0.0, 0, 0], [0, 0, 3]]))
        >>> d.tolist(), i.tolist()
        ([1.0], [0])
    """
    distance, index = cKDTree(reference).query(query, k=1)
    return np.asarray(distance, np.float64), np.asarray(index, np.int64)


def chamfer_l1(pred: np.ndarray, true: np.ndarray) -> float | None:
    """Chamfer-L1 of (N, 3) predicted and (M, 3) true points: the mean of the two directed mean nearest-point
    distances; ``None`` when either side is empty.

    Example:
        >>> chamfer_l1(np.array([[0.0, 0, 0]]), np.array([[0.0, 0, 0], [0, 0, 2]]))
        0.5
    """
    if len(pred) == 0 or len(true) == 0:
        return None
    return chamfer_from_distances(nearest(pred, true)[0], nearest(true, pred)[0])


def chamfer_from_distances(pred_to_true: np.ndarray, true_to_pred: np.ndarray) -> float:
    """Chamfer-L1 from the (N,) nearest distances of predicted points and the (M,) ones of true points."""
    return float(0.5 * (pred_to_true.mean() + true_to_pred.mean()))


def fscore_from_distances(pred_to_true: np.ndarray, true_to_pred: np.ndarray, tau: float = FSCORE_TAU) -> float:
    """F-score at ``tau`` from the (N,) nearest distances of predicted points and the (M,) ones of true points
    (0 when either is empty).

    Example:
        >>> fscore_from_distances(np.array([0.0, 1.0]), np.array([0.005]))  # P = 1/2, R = 1
        0.6666666666666666
    """
    if len(pred_to_true) == 0 or len(true_to_pred) == 0:
        return 0.0
    precision = float((pred_to_true <= tau).mean())
    recall = float((true_to_pred <= tau).mean())
    return 0.0 if precision + recall == 0 else 2 * precision * recall / (precision + recall)


def fscore(pred: np.ndarray, true: np.ndarray, tau: float = FSCORE_TAU) -> float:
    """F-score at ``tau`` of (N, 3) predicted and (M, 3) true points: the harmonic mean of precision (predicted
    points within ``tau`` of a true point) and recall (true points within ``tau`` of a predicted point); 0 when
    either side is empty or nothing is within ``tau``.

    Example:
        >>> fscore(np.array([[0.0, 0, 0], [1, 0, 0]]), np.array([[0.0, 0, 0.005]]))  # P = 1/2, R = 1
        0.6666666666666666
    """
    if len(pred) == 0 or len(true) == 0:
        return 0.0
    return fscore_from_distances(nearest(pred, true)[0], nearest(true, pred)[0], tau)


def transferred_labels(pred: SurfaceSamples, true_points: np.ndarray) -> np.ndarray:
    """(M,) label of the predicted point nearest to each true point (all background, 0, without predicted
    points)."""
    if len(pred) == 0:
        return np.zeros(len(true_points), np.int64)
    return pred.labels[nearest(true_points, pred.points)[1]]


def label_miou(true_labels: np.ndarray, pred_labels: np.ndarray, background: int = 0) -> float | None:
    """Mean IoU over the classes present in ``true_labels`` other than ``background``, of two (M,) label arrays
    on the same points; ``None`` when the truth has no such class.

    Example:
        >>> label_miou(np.array([1, 1, 2, 2]), np.array([1, 2, 2, 2]))  # IoU 1/2 and 2/3
        0.5833333333333333
    """
    classes = [c for c in np.unique(true_labels).tolist() if c != background]
    if not classes:
        return None
    ious = []
    for c in classes:
        t, p = true_labels == c, pred_labels == c
        ious.append(float((t & p).sum() / (t | p).sum()))
    return float(np.mean(ious))


def affordance_miou_3d(pred: SurfaceSamples, true: SurfaceSamples, background: int = 0) -> float | None:
    """3D affordance mIoU: every true point takes the label of its nearest predicted point, then
    :func:`label_miou` (0 for an empty prediction; ``None`` when the truth has no affordance class)."""
    return label_miou(true.labels, transferred_labels(pred, true.points), background)


def surface_metrics(pred: SurfaceSamples, true: SurfaceSamples, tau: float = FSCORE_TAU) -> dict[str, float | None]:
    """The three 3D metrics (keys :data:`SURFACE_KEYS`) of predicted against true surface samples, from one
    nearest-point search each way."""
    if len(pred) == 0 or len(true) == 0:
        return {"chamfer_l1": None, "fscore_1cm": 0.0, "affordance_miou_3d": affordance_miou_3d(pred, true)}
    pred_to_true = nearest(pred.points, true.points)[0]
    true_to_pred, index = nearest(true.points, pred.points)
    return {
        "chamfer_l1": chamfer_from_distances(pred_to_true, true_to_pred),
        "fscore_1cm": fscore_from_distances(pred_to_true, true_to_pred, tau),
        "affordance_miou_3d": label_miou(true.labels, pred.labels[index]),
    }
