"""Viewpoints of the canonical frame: cameras on the upper hemisphere looking at the origin, parametrised by
azimuth, elevation and distance (conventions §1), and the silhouettes a point set casts through them.

Used by test-time inversion (:mod:`affnerf.predict.invert`) to find the unknown camera of an input photo.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import torch


def camera_pose(azimuth: torch.Tensor, elevation: torch.Tensor, distance: torch.Tensor) -> torch.Tensor:
    """(4, 4) camera-to-world pose looking at the origin from the given angles (rad) and distance, +z up in the
    image (the convention of :func:`affnerf.data.cameras.look_at`); differentiable in all three.

    Example:
        >>> p = camera_pose(torch.tensor(0.0), torch.tensor(0.0), torch.tensor(1.0))
        >>> p[:3, 3].tolist(), p[:3, 2].tolist()
        ([1.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    """
    ce, se, ca, sa = torch.cos(elevation), torch.sin(elevation), torch.cos(azimuth), torch.sin(azimuth)
    back = torch.stack([ce * ca, ce * sa, se])
    right = torch.stack([-sa, ca, torch.zeros_like(sa)])
    up = torch.linalg.cross(back, right)
    top = torch.stack([right, up, back, distance * back], dim=1)
    bottom = torch.tensor([[0.0, 0.0, 0.0, 1.0]], dtype=top.dtype, device=top.device)
    return torch.cat([top, bottom], dim=0)


def camera_grid(azimuths: int, elevations_deg: Sequence[float], distances: Sequence[float]) -> np.ndarray:
    """(N, 3) (azimuth rad, elevation rad, distance m) of every camera of a search grid: ``azimuths`` evenly
    spaced over the full turn, times the elevations, times the distances.

    Example:
        >>> camera_grid(4, [30.0], [0.5, 0.7]).shape
        (8, 3)
    """
    az = np.arange(azimuths) * (2.0 * math.pi / azimuths)
    el = np.radians(np.asarray(elevations_deg, np.float64))
    grid = np.meshgrid(az, el, np.asarray(distances, np.float64), indexing="ij")
    return np.stack([g.ravel() for g in grid], axis=1)


def project_points(
    points: np.ndarray, cameras: np.ndarray, intrinsics: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixel coordinates of a point set seen by many cameras through one crop.

    Args:
        points: (P, 3) canonical points.
        cameras: (N, 3) azimuth, elevation, distance of each camera (looking at the origin).
        intrinsics: (4,) crop intrinsics (fx, fy, cx, cy).

    Returns:
        (N, P) float column u and row v of each point in each camera's image (pixel edges at integers), and (N, P)
        bool, True where the point lies in front of the camera.

    Example:
        >>> u, v, front = project_points(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.array([10, 10, 16, 16]))
        >>> float(u[0, 0]), float(v[0, 0]), bool(front[0, 0])
        (16.0, 16.0, True)
    """
    az, el, dist = cameras[:, 0], cameras[:, 1], cameras[:, 2]
    back = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], 1)  # (N, 3)
    right = np.stack([-np.sin(az), np.cos(az), np.zeros_like(az)], 1)
    up = np.cross(back, right)
    rel = points[None] - (dist[:, None] * back)[:, None]  # (N, P, 3) from the eye
    x, y, z = (np.einsum("npk,nk->np", rel, axis) for axis in (right, up, back))
    depth = np.maximum(-z, 1e-6)
    return x / depth * intrinsics[0] + intrinsics[2], -y / depth * intrinsics[1] + intrinsics[3], z < 0


def project_silhouettes(points: np.ndarray, cameras: np.ndarray, intrinsics: np.ndarray, size: int) -> np.ndarray:
    """Binary silhouettes of a point set seen by many cameras through one crop.

    Args:
        points: (P, 3) canonical points inside the object.
        cameras: (N, 3) azimuth, elevation, distance of each camera (looking at the origin).
        intrinsics: (4,) crop intrinsics at side ``size``.
        size: the silhouettes' side in pixels.

    Returns:
        (N, size, size) bool, True where at least one point projects.
    """
    u, v, front = project_points(points, cameras, intrinsics)
    u, v = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
    keep = (u >= 0) & (u < size) & (v >= 0) & (v < size) & front
    out = np.zeros((len(cameras), size * size), bool)
    rows = np.broadcast_to(np.arange(len(cameras))[:, None], u.shape)
    out[rows[keep], (v * size + u)[keep]] = True
    return out.reshape(len(cameras), size, size)


def silhouette_iou(silhouettes: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(N,) IoU of each of (N, S, S) silhouettes with an (S, S) bool mask."""
    inter = (silhouettes & mask[None]).sum(axis=(1, 2))
    union = (silhouettes | mask[None]).sum(axis=(1, 2))
    return inter / np.maximum(union, 1)
