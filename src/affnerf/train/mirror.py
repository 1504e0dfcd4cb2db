"""Mirror augmentation: an encoded view flipped left-right, with the object's supervision mirrored to match.

A left-right flip of a photo is a photo of the mirror image of the scene. The cameras look at the object with world
+z up and no roll, so the plane that the flip mirrors the scene across is vertical, and the mirror image of the
object is, up to a turn about +z, its mirror image across any vertical plane through the origin: x = 0 or y = 0.
The model predicts objects in their category's orientation (conventions §1), so the flipped view shows the object
mirrored across the one of those planes that keeps that orientation: the plane the object is (nearly) symmetric
about. For a symmetric object the flipped view is a view from another side of the same object, and the targets do
not change; for a nearly symmetric one (a cabinet with its handles on one side, scissors whose blades cross one way)
the targets are mirrored with it. :func:`mirror_axis` finds the plane from the object's own supervision points; the
sampler (:class:`affnerf.train.sampler.RaySampler`, ``mirror_fraction``) flips the crop and mirrors the rays, the
encoded camera and the 3D points (:func:`reflection`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from affnerf.train.points import PointSet

#: points within this distance of the surface (m) stand for it in :func:`mirror_asymmetry`.
SURFACE_BAND = 0.002
#: at most this many surface points are compared (drawn evenly over the set).
SURFACE_POINTS = 4000
#: an object this close to its mirror image (:func:`mirror_asymmetry`) across a plane is mirrored across it.
SYMMETRIC = 0.25
#: otherwise its better plane must be at most this share of the other's asymmetry, and at most MAX_ASYMMETRY (a
#: cabinet with drawers on one side keeps its front facing -y mirrored across x = 0, not across y = 0).
CLEARER = 0.6
MAX_ASYMMETRY = 1.0
#: distance (m) that counts as much as a label mismatch of every point in :func:`mirror_asymmetry`.
DISTANCE_SCALE = 0.05


def mirror_asymmetry(points: PointSet, axis: int) -> float:
    """How far an object is from its mirror image across the plane where coordinate ``axis`` is 0: over its
    surface points, the share whose mirror image's nearest surface point has another label, plus the mean distance
    to that point over :data:`DISTANCE_SCALE`. About 0.1 for a symmetric object (the points' own spacing).

    Example:
        >>> rng = np.random.default_rng(0)
        >>> xyz = rng.uniform(-0.05, 0.05, (3000, 3)).astype(np.float32)  # 3,000 points 7 mm apart
        >>> labels = np.where(xyz[:, 0] > 0, 1, 2).astype(np.uint8)  # two halves along x
        >>> cube = PointSet(xyz, np.zeros(3000, np.uint8), labels, np.zeros(3000, np.float16))
        >>> round(mirror_asymmetry(cube, 1), 2), round(mirror_asymmetry(cube, 0), 2)
        (0.1, 1.04)
    """
    near = np.flatnonzero(np.abs(np.asarray(points.distance, np.float32)) < SURFACE_BAND)
    near = near[np.linspace(0, len(near) - 1, min(len(near), SURFACE_POINTS)).astype(int)] if len(near) else near
    if len(near) < 2:
        return float("inf")
    xyz = np.asarray(points.points[near], np.float64)
    labels = np.asarray(points.labels[near])
    mirrored = xyz.copy()
    mirrored[:, axis] *= -1.0
    distance, nearest = cKDTree(xyz).query(mirrored)
    return float(np.mean(labels[nearest] != labels) + np.mean(distance) / DISTANCE_SCALE)


def mirror_axis(points: PointSet) -> int:
    """The canonical axis (0 = x, 1 = y) whose sign a mirror of the object flips: the vertical plane it is most
    symmetric about (:func:`mirror_asymmetry`), when it is symmetric about it (:data:`SYMMETRIC`) or clearly more so
    than about the other (:data:`CLEARER`, :data:`MAX_ASYMMETRY`); -1 otherwise (never mirrored)."""
    scores = [mirror_asymmetry(points, axis) for axis in (0, 1)]
    best = int(np.argmin(scores))
    clearer = scores[best] <= min(CLEARER * scores[1 - best], MAX_ASYMMETRY)
    return best if scores[best] <= SYMMETRIC or clearer else -1


def reflection(axis: int) -> np.ndarray:
    """(3,) signs that mirror canonical points across the plane where coordinate ``axis`` is 0 (all ones for -1).

    Example:
        >>> reflection(1).tolist()
        [1.0, -1.0, 1.0]
        >>> reflection(-1).tolist()
        [1.0, 1.0, 1.0]
    """
    signs = np.ones(3)
    if axis >= 0:
        signs[axis] = -1.0
    return signs


def mirrored_poses(poses: np.ndarray, signs: np.ndarray) -> np.ndarray:
    """(V, 4, 4) camera-to-world poses of the flipped views of the mirrored object: the world mirrored by ``signs``
    and the camera's own x axis turned round, which keeps each rotation proper (det +1) and puts a mirrored point
    at the flipped pixel (u -> width - u)."""
    world = np.diag([*signs, 1.0])
    camera_x = np.diag([-1.0, 1.0, 1.0, 1.0])
    return world @ poses @ camera_x


def flipped_crop_intrinsics(intrinsics: np.ndarray, size: int) -> np.ndarray:
    """(V, 4) fl_x, fl_y, cx, cy of crops of ``size`` pixels flipped left-right: cx -> size - cx."""
    out = np.array(intrinsics, np.float64, copy=True)
    out[:, 2] = size - out[:, 2]
    return out


def flipped_views(
    crops: np.ndarray,
    intrinsics: np.ndarray,
    poses: np.ndarray,
    depth: np.ndarray,
    labels: np.ndarray,
    signs: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """The encoded views of one object flipped left-right, as views of its mirror image across ``signs``
    (:func:`reflection`): (V, S, S, 3) crops, (V, 4) crop intrinsics, (V, 4, 4) poses, (V, S, S) depth and
    labels."""
    size = crops.shape[2]
    return (
        np.ascontiguousarray(crops[:, :, ::-1]),
        flipped_crop_intrinsics(intrinsics, size),
        mirrored_poses(poses, signs),
        np.ascontiguousarray(depth[:, :, ::-1]),
        np.ascontiguousarray(labels[:, :, ::-1]),
    )
