"""Cameras (conventions §1): pinhole intrinsics, camera-to-world poses on the upper hemisphere, and pixel rays.

Poses are camera-to-world in the OpenGL/Blender convention: the camera looks along its -z axis, +y is up and
+x right. Pixel (u, v) has its centre at (u + 0.5, v + 0.5); its ray has camera-frame direction
((u + 0.5 - cx) / fl_x, -(v + 0.5 - cy) / fl_y, -1).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

#: Near and far bounds of every ray, metres (conventions §1).
NEAR, FAR = 0.1, 1.5


@dataclass(frozen=True)
class Intrinsics:
    """A pinhole camera's image size and intrinsics, in pixels."""

    width: int
    height: int
    fl_x: float
    fl_y: float
    cx: float
    cy: float

    @classmethod
    def from_fov(cls, width: int, height: int, camera_angle_x: float) -> Intrinsics:
        """Square pixels, principal point at the image centre, horizontal field of view in radians."""
        fl = 0.5 * width / math.tan(0.5 * camera_angle_x)
        return cls(width, height, fl, fl, width / 2.0, height / 2.0)

    @property
    def camera_angle_x(self) -> float:
        """Horizontal field of view in radians."""
        return 2.0 * math.atan(0.5 * self.width / self.fl_x)

    def scaled(self, factor: float) -> Intrinsics:
        """The same camera at ``factor`` times the resolution (sizes rounded to whole pixels)."""
        w, h = max(1, round(self.width * factor)), max(1, round(self.height * factor))
        sx, sy = w / self.width, h / self.height
        return Intrinsics(w, h, self.fl_x * sx, self.fl_y * sy, self.cx * sx, self.cy * sy)


#: Default horizontal field of view (radians): 60 degrees, which keeps objects of the canonical cube in view
#: from 0.5 m.
DEFAULT_CAMERA_ANGLE_X = math.radians(60.0)


def look_at(eye: np.ndarray, target: np.ndarray, up: np.ndarray | None = None) -> np.ndarray:
    """Camera-to-world (4, 4) of a camera at ``eye`` looking at ``target`` with ``up`` (default +z) roughly up in
    the image.

    Example:
        >>> look_at(np.array([0, 0, 1.0]), np.zeros(3), up=np.array([0, 1.0, 0]))[:3, 2].tolist()
        [0.0, 0.0, 1.0]
    """
    back = np.asarray(eye, np.float64) - np.asarray(target, np.float64)
    back /= np.linalg.norm(back)
    right = np.cross(np.array([0.0, 0.0, 1.0]) if up is None else up, back)
    if np.linalg.norm(right) < 1e-8:  # looking straight along up: pick any right vector
        right = np.cross(np.array([0.0, 1.0, 0.0]), back)
    right /= np.linalg.norm(right)
    true_up = np.cross(back, right)
    c2w = np.eye(4)
    c2w[:3, 0], c2w[:3, 1], c2w[:3, 2], c2w[:3, 3] = right, true_up, back, eye
    return c2w


@dataclass(frozen=True)
class CameraSampler:
    """Where cameras go: on the upper hemisphere around the origin, looking at it (conventions §1).

    Attributes:
        elevation_deg: range of elevation above the xy plane, degrees.
        radius: range of distance from the origin, metres.
        jitter: standard deviation of the random offset of the look-at point, metres.
    """

    elevation_deg: tuple[float, float] = (10.0, 80.0)
    radius: tuple[float, float] = (0.5, 0.9)
    jitter: float = 0.015

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """(n, 4, 4) camera-to-world poses with random yaw, elevation, radius and look-at jitter."""
        yaw = rng.uniform(0.0, 2.0 * np.pi, n)
        elev = np.radians(rng.uniform(*self.elevation_deg, n))
        radius = rng.uniform(*self.radius, n)
        targets = rng.normal(0.0, self.jitter, (n, 3))
        eyes = radius[:, None] * np.stack([np.cos(elev) * np.cos(yaw), np.cos(elev) * np.sin(yaw), np.sin(elev)], 1)
        return np.stack([look_at(e, t) for e, t in zip(eyes, targets, strict=True)])


@functools.lru_cache(maxsize=8)
def _cached_directions(intr: Intrinsics) -> np.ndarray:
    u = (np.arange(intr.width) + 0.5 - intr.cx) / intr.fl_x
    v = -(np.arange(intr.height) + 0.5 - intr.cy) / intr.fl_y
    uu, vv = np.meshgrid(u, v)
    dirs = np.stack([uu, vv, -np.ones_like(uu)], -1)
    dirs.flags.writeable = False
    return dirs


def pixel_directions(intr: Intrinsics) -> np.ndarray:
    """(H, W, 3) camera-frame ray directions through pixel centres, with z = -1 (not normalised; read-only, cached).

    Example:
        >>> pixel_directions(Intrinsics(2, 2, 1.0, 1.0, 1.0, 1.0))[0, 0].tolist()
        [-0.5, 0.5, -1.0]
    """
    return _cached_directions(intr)


def world_rays(intr: Intrinsics, c2w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World-frame rays of every pixel.

    Returns:
        origins (H*W, 3) and directions (H*W, 3); a direction's component along the camera's -z axis is 1, so
        a hit at ray parameter t has z-depth exactly t.
    """
    dirs = pixel_directions(intr).reshape(-1, 3) @ c2w[:3, :3].T
    origins = np.broadcast_to(c2w[:3, 3], dirs.shape).copy()
    return origins, dirs


def project(points: np.ndarray, intr: Intrinsics, c2w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Project world points into an image.

    Args:
        points: (N, 3) world points.
        intr: the camera's intrinsics.
        c2w: (4, 4) its camera-to-world pose.

    Returns:
        pixel coordinates (N, 2) as continuous (x, y) with pixel centres at half-integers, and z-depths (N,)
        (positive in front of the camera).
    """
    w2c = np.linalg.inv(c2w)
    cam = points @ w2c[:3, :3].T + w2c[:3, 3]
    depth = -cam[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = cam[:, 0] / depth * intr.fl_x + intr.cx
        y = -cam[:, 1] / depth * intr.fl_y + intr.cy
    return np.stack([x, y], 1), depth


def unproject_depth(depth: np.ndarray, intr: Intrinsics, c2w: np.ndarray) -> np.ndarray:
    """(H, W, 3) world points of a z-depth map (metres): pixel centre direction times depth."""
    cam = pixel_directions(intr) * depth[..., None]
    return cam @ c2w[:3, :3].T + c2w[:3, 3]
