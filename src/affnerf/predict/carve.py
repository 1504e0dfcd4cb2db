"""Silhouette carving: keep only what the input photo can contain (a one-view visual hull).

A shape predicted from one photo may put matter where the photo shows background: a bottle's body too wide seen
from the front, a handle beside the object. Once the fit to the photo (:mod:`affnerf.predict.invert`) has found
the camera of the encoders' crop, every point of the canonical frame can be projected into the crop; a point that
falls on the background (beyond a margin for the camera's error) cannot be on the object, whatever the decoder
says. This is the visual hull of space carving (Laurentini 1994; Kutulakos and Seitz 2000) from the views that were
fitted: each view carves, several views carve their intersection. Points behind a camera are never carved.

The carving is an :class:`~affnerf.rendering.grid.OccupancyGrid` whose ``lookup`` also asks the hull, so rendering
(empty-space skipping) and mesh extraction, which both ask the grid, see the same carved object.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch
import torch.nn.functional as F

from affnerf.predict.viewpoint import camera_pose
from affnerf.rendering.grid import OccupancyGrid

#: Margin around the photo's silhouette that is never carved, as a share of the crop's side: room for the error of
#: the fitted camera and of the mask's edge.
CARVE_MARGIN = 0.04

#: Side (pixels) of the crop whose mask carves: finer than the encoders' crop, so thin parts keep their outline.
CARVE_RESOLUTION = 128


@dataclass(frozen=True)
class SilhouetteView:
    """One fitted view: the crop's mask and the camera that sees it.

    Attributes:
        mask: (S, S) bool, True on the object, in the crop.
        intrinsics: (4,) fl_x, fl_y, cx, cy of the crop at side S.
        camera: (3,) azimuth (rad), elevation (rad), distance (m) of the crop's camera in the canonical frame.
    """

    mask: np.ndarray
    intrinsics: np.ndarray
    camera: tuple[float, float, float]


def project_points(points: torch.Tensor, camera: tuple[float, float, float], intrinsics: np.ndarray) -> tuple:
    """Pixel coordinates of (P, 3) canonical points seen by a camera looking at the origin (OpenGL convention).

    Returns:
        u (P,), v (P,) float pixel coordinates (column, row; pixel centres at +0.5) and in_front (P,) bool.

    Example:
        >>> u, v, front = project_points(torch.zeros(1, 3), (0.0, 0.0, 1.0), np.array([10.0, 10.0, 8.0, 8.0]))
        >>> float(u[0]), float(v[0]), bool(front[0])
        (8.0, 8.0, True)
    """
    pose = camera_pose(*(torch.tensor(float(c), dtype=torch.float64) for c in camera)).to(points.device)
    rel = points.double() - pose[:3, 3]
    x, y, z = (rel @ pose[:3, i] for i in range(3))
    depth = (-z).clamp_min(1e-9)
    k = [float(c) for c in intrinsics]
    return x / depth * k[0] + k[2], -y / depth * k[1] + k[3], z < 0


def grown_mask(mask: np.ndarray, margin: float) -> torch.Tensor:
    """(S, S) bool ``mask`` grown by ``margin`` times its side (a square neighbourhood), as a tensor.

    Example:
        >>> m = np.zeros((10, 10), bool); m[5, 5] = True
        >>> int(grown_mask(m, 0.1).sum())
        9
    """
    radius = int(round(margin * mask.shape[0]))
    t = torch.from_numpy(np.ascontiguousarray(mask, np.float32))[None, None]
    if radius > 0:
        t = F.max_pool2d(t, 2 * radius + 1, stride=1, padding=radius)
    return t[0, 0] > 0


def inside_silhouette(points: torch.Tensor, view: SilhouetteView, grown: torch.Tensor) -> torch.Tensor:
    """(P,) bool: whether each of (P, 3) points projects onto ``grown`` (the view's grown mask) or lies behind the
    camera; points projecting outside the crop are outside (the crop frames the whole object with a margin)."""
    u, v, front = project_points(points, view.camera, view.intrinsics)
    size = grown.shape[0]
    col, row = torch.floor(u).long(), torch.floor(v).long()
    within = (col >= 0) & (col < size) & (row >= 0) & (row < size)
    hit = grown.to(points.device)[row.clamp(0, size - 1), col.clamp(0, size - 1)] & within
    return hit | ~front


@dataclass
class CarvedGrid(OccupancyGrid):
    """An occupancy grid carved by the silhouettes of fitted views: a point is occupied when its cell is and it
    projects inside every view's grown mask (see the module docstring).

    Attributes:
        views: the fitted views.
        margin: growth of each mask, as a share of its side (:data:`CARVE_MARGIN`).
    """

    views: list[SilhouetteView] = field(default_factory=list)
    margin: float = CARVE_MARGIN

    def __post_init__(self) -> None:
        self._grown = [grown_mask(v.mask, self.margin) for v in self.views]

    def lookup(self, points: torch.Tensor) -> torch.Tensor:
        keep = super().lookup(points)
        for view, grown in zip(self.views, self._grown, strict=True):
            keep = keep & inside_silhouette(points, view, grown)
        return keep


def carve(grid: OccupancyGrid, views: list[SilhouetteView], margin: float = CARVE_MARGIN) -> CarvedGrid:
    """``grid`` carved by the silhouettes of ``views`` (its cells are kept; the carving is per point)."""
    return CarvedGrid(grid.occupied, grid.half_extent, list(views), margin)
