"""The input camera as seven numbers, predicted from an object crop (the pose-aware model, conventions §4).

The datasets' cameras sit on a sphere around the canonical origin, look at it and keep +z up (conventions §1), so
the camera of an object-centred crop is fixed, up to the look-at point's small jitter, by

    elevation (rad) | cos azimuth | sin azimuth | log distance (m) | log focal / S | principal x / S | principal y / S

where focal and principal point are the crop's intrinsics in pixels of the S x S crop, and the principal point is
where the canonical origin appears in the crop (a look-at camera puts the origin on its optical axis). These
functions convert between that vector and (world-to-camera, intrinsics) pairs, and score a prediction against the
truth. All are batched and differentiable.
"""

from __future__ import annotations

import math

import torch
from torch.nn import functional as F

__all__ = [
    "CAMERA_PARAMS",
    "PARAM_PRIOR",
    "azimuth_cosine",
    "camera_from_params",
    "camera_loss",
    "camera_errors",
    "params_from_camera",
]

#: Length of the camera vector.
CAMERA_PARAMS = 7
#: A typical camera of the datasets (45° elevation, azimuth 0, 0.7 m away, focal 2.5 crop sides, origin at the
#: crop's centre): what an untrained head predicts, so training starts from a plausible projection.
PARAM_PRIOR = (math.radians(45.0), 1.0, 0.0, math.log(0.7), math.log(2.5), 0.5, 0.5)
#: Elevations are kept inside this many radians of the horizon, so the look-at frame stays defined.
MAX_ELEVATION = math.radians(85.0)


def params_from_camera(c2w: torch.Tensor, intrinsics: torch.Tensor, size: int) -> torch.Tensor:
    """True camera vectors of crops.

    Args:
        c2w: (..., 4, 4) camera-to-world poses in the canonical frame.
        intrinsics: (..., 4) crop intrinsics (fl_x, fl_y, cx, cy) in pixels of the crop.
        size: the crop side S.

    Returns:
        (..., 7) camera vectors (module docstring).
    """
    eye = c2w[..., :3, 3]
    dist = eye.norm(dim=-1).clamp(min=1e-6)
    elevation = torch.asin((eye[..., 2] / dist).clamp(-1.0, 1.0))
    azimuth = torch.atan2(eye[..., 1], eye[..., 0])
    w2c_t = -(c2w[..., :3, :3].transpose(-1, -2) @ eye[..., None])[..., 0]  # the origin in the camera frame
    depth = (-w2c_t[..., 2]).clamp(min=1e-6)
    u = intrinsics[..., 0] * w2c_t[..., 0] / depth + intrinsics[..., 2]
    v = -intrinsics[..., 1] * w2c_t[..., 1] / depth + intrinsics[..., 3]
    focal = 0.5 * (intrinsics[..., 0] + intrinsics[..., 1]) / size
    return torch.stack([elevation, azimuth.cos(), azimuth.sin(), dist.log(), focal.log(), u / size, v / size], dim=-1)


def camera_from_params(params: torch.Tensor, size: int) -> tuple[torch.Tensor, torch.Tensor]:
    """The look-at camera a vector describes.

    Args:
        params: (..., 7) camera vectors; the azimuth pair need not be unit length.
        size: the crop side S.

    Returns:
        (..., 4, 4) world-to-camera transforms and (..., 4) crop intrinsics (fl, fl, cx, cy).
    """
    elevation = params[..., 0].clamp(-MAX_ELEVATION, MAX_ELEVATION)
    azimuth = F.normalize(params[..., 1:3], dim=-1, eps=1e-6)
    dist = params[..., 3].exp()
    back = torch.stack([elevation.cos() * azimuth[..., 0], elevation.cos() * azimuth[..., 1], elevation.sin()], dim=-1)
    up = torch.zeros_like(back)
    up[..., 2] = 1.0
    right = F.normalize(torch.cross(up, back, dim=-1), dim=-1, eps=1e-6)
    true_up = torch.cross(back, right, dim=-1)
    rot = torch.stack([right, true_up, back], dim=-1)  # camera-to-world rotation, columns = camera axes
    eye = dist[..., None] * back
    w2c = torch.zeros(*params.shape[:-1], 4, 4, dtype=params.dtype, device=params.device)
    w2c[..., :3, :3] = rot.transpose(-1, -2)
    w2c[..., :3, 3] = -(rot.transpose(-1, -2) @ eye[..., None])[..., 0]
    w2c[..., 3, 3] = 1.0
    focal = params[..., 4].exp() * size
    intrinsics = torch.stack([focal, focal, params[..., 5] * size, params[..., 6] * size], dim=-1)
    return w2c, intrinsics


def azimuth_cosine(pred: torch.Tensor, true: torch.Tensor) -> torch.Tensor:
    """(N,) cosine of the azimuth error of (N, 7) predicted camera vectors (their azimuth pair taken by direction
    only) against the true ones."""
    return (F.normalize(pred[:, 1:3], dim=-1, eps=1e-6) * true[:, 1:3]).sum(-1)


def camera_loss(pred: torch.Tensor, true: torch.Tensor) -> torch.Tensor:
    """0-d loss of (N, 7) predicted camera vectors against the true ones: L1 on elevation, log distance, log focal
    and principal point, plus 1 - cos of the azimuth error (an azimuth pair is compared by direction only)."""
    azimuth = 1.0 - azimuth_cosine(pred, true)
    scalars = (pred[:, [0, 3, 4, 5, 6]] - true[:, [0, 3, 4, 5, 6]]).abs().sum(-1)
    return (azimuth + scalars).mean()


def camera_errors(pred: torch.Tensor, true: torch.Tensor) -> dict[str, torch.Tensor]:
    """Per-crop errors of (N, 7) predicted camera vectors: ``elevation_deg``, ``azimuth_deg`` (0..180),
    ``distance_rel`` (|log ratio|) and ``principal`` (distance in crop sides), each (N,)."""
    cos = azimuth_cosine(pred, true).clamp(-1.0, 1.0)
    return {
        "elevation_deg": torch.rad2deg((pred[:, 0] - true[:, 0]).abs()),
        "azimuth_deg": torch.rad2deg(torch.acos(cos)),
        "distance_rel": (pred[:, 3] - true[:, 3]).abs(),
        "principal": (pred[:, 5:7] - true[:, 5:7]).norm(dim=-1),
    }
