"""Rendering whole images of an encoded object from any camera, in chunks of rays so any size fits in memory."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from affnerf.data.cameras import Intrinsics
from affnerf.model.affnerf import Codes
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import RAYS_PER_CHUNK
from affnerf.rendering.grid import OccupancyGrid
from affnerf.rendering.rays import pixel_rays


@dataclass
class RenderedView:
    """One rendered view.

    Attributes:
        rgb: (H, W, 3) float colours in [0, 1].
        depth: (H, W) z-depth in metres where the pixel is mostly opaque (opacity > 0.5), else 0.
        opacity: (H, W) accumulated opacity.
        affordance: (H, W, C) class probabilities (class 0 background).
    """

    rgb: np.ndarray
    depth: np.ndarray
    opacity: np.ndarray
    affordance: np.ndarray

    @property
    def labels(self) -> np.ndarray:
        """(H, W) most likely class per pixel."""
        return self.affordance.argmax(axis=-1).astype(np.uint8)


def camera_rays(intrinsics: Intrinsics, c2w: np.ndarray) -> tuple[torch.Tensor, torch.Tensor]:
    """Rays through every pixel of a camera, row by row: (H*W, 3) origins and directions, float64."""
    vv, uu = np.mgrid[0 : intrinsics.height, 0 : intrinsics.width]
    pixels = torch.from_numpy(np.stack([uu.ravel(), vv.ravel()], 1))
    k = torch.tensor([intrinsics.fl_x, intrinsics.fl_y, intrinsics.cx, intrinsics.cy], dtype=torch.float64)
    return pixel_rays(pixels, k, torch.as_tensor(np.asarray(c2w), dtype=torch.float64))


@torch.no_grad()
def render_view(
    model: ConditionedNeRF,
    encoding: Codes | Any,
    intrinsics: Intrinsics,
    c2w: np.ndarray,
    background: tuple[float, float, float] | np.ndarray = (1.0, 1.0, 1.0),
    chunk: int = RAYS_PER_CHUNK,
    grid: OccupancyGrid | None = None,
    grid_samples: int = 32,
) -> RenderedView:
    """Render every pixel of a camera for one object.

    Args:
        model: the trained model (evaluation mode is the caller's business).
        encoding: the object's encoding (``model.encode_views`` of one object; AFF-NeRF's codes).
        intrinsics: the camera.
        c2w: (4, 4) camera-to-world pose in the canonical frame.
        background: RGB in [0, 1].
        chunk: rays per forward pass.
        grid: the object's occupancy grid: render with empty-space skipping, ``grid_samples`` per ray (fast path);
            None renders coarse-to-fine as in training.
    """
    device = next(model.parameters()).device
    h, w = intrinsics.height, intrinsics.width
    origins, dirs = camera_rays(intrinsics, c2w)
    bg = torch.as_tensor(np.asarray(background), dtype=torch.float32, device=device)
    rgb, depth, opacity, aff = [], [], [], []
    for start in range(0, h * w, chunk):
        o = origins[start : start + chunk].float().to(device)
        d = dirs[start : start + chunk].float().to(device)
        n = o.shape[0]
        if grid is not None:
            out = model.render_rays_in_grid(encoding, grid, o, d, bg.expand(n, 3), grid_samples)
        else:
            coarse, fine = model.render_rays(
                encoding, torch.zeros(n, dtype=torch.long, device=device), o, d, bg.expand(n, 3)
            )
            out = fine if fine is not None else coarse
        rgb.append(out.rgb.cpu())
        opacity.append(out.opacity.cpu())
        depth.append((out.depth / out.opacity.clamp(min=1e-6)).cpu())
        aff.append(out.affordance.cpu())
    alpha = torch.cat(opacity).reshape(h, w).numpy()
    z = torch.cat(depth).reshape(h, w).numpy()
    return RenderedView(
        rgb=torch.cat(rgb).reshape(h, w, 3).clamp(0, 1).numpy(),
        depth=np.where(alpha > 0.5, z, 0.0).astype(np.float32),
        opacity=alpha,
        affordance=torch.cat(aff).reshape(h, w, -1).numpy(),
    )
