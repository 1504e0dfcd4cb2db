"""Rays of pixels (conventions §1) and their intersection with the canonical cube, in torch."""

from __future__ import annotations

import torch


def pixel_rays(pixels: torch.Tensor, intrinsics: torch.Tensor, c2w: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """World rays through pixel centres.

    Args:
        pixels: (R, 2) integer or float (u, v) pixel indices; the ray passes through (u + 0.5, v + 0.5).
        intrinsics: (R, 4) or (4,) (fl_x, fl_y, cx, cy).
        c2w: (R, 4, 4) or (4, 4) camera-to-world poses (OpenGL convention: the camera looks along -z).

    Returns:
        origins (R, 3) and directions (R, 3); each direction has unit length along the camera's -z axis, so the
        ray parameter of a point is its z-depth.

    Example:
        >>> o, d = pixel_rays(torch.tensor([[1, 1]]), torch.tensor([1.0, 1.0, 1.0, 1.0]), torch.eye(4))
        >>> d.tolist()
        [[0.5, -0.5, -1.0]]
    """
    k = intrinsics.expand(pixels.shape[0], 4) if intrinsics.dim() == 1 else intrinsics
    pose = c2w.expand(pixels.shape[0], 4, 4) if c2w.dim() == 2 else c2w
    pixels = pixels.to(k.dtype)
    x = (pixels[:, 0] + 0.5 - k[:, 2]) / k[:, 0]
    y = -(pixels[:, 1] + 0.5 - k[:, 3]) / k[:, 1]
    cam = torch.stack([x, y, -torch.ones_like(x)], dim=-1)
    dirs = torch.einsum("rij,rj->ri", pose[:, :3, :3], cam)
    return pose[:, :3, 3].clone(), dirs


def intersect_aabb(
    origins: torch.Tensor, dirs: torch.Tensor, half_extent: float, near: float, far: float
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Clip rays to the axis-aligned cube [-half_extent, half_extent]^3 (slab method), within [near, far].

    Args:
        origins: (R, 3).
        dirs: (R, 3), any length (t is in units of it).
        half_extent: half the cube's side.
        near: smallest allowed t.
        far: largest allowed t.

    Returns:
        t_near (R,), t_far (R,), and hit (R,) bool: whether the ray crosses the cube inside [near, far]. Rays that
        miss get t_near = t_far = far.

    Example:
        >>> tn, tf, hit = intersect_aabb(torch.tensor([[0.0, 0, 1]]), torch.tensor([[0.0, 0, -1]]), 0.25, 0.1, 1.5)
        >>> tn.tolist(), tf.tolist(), hit.tolist()
        ([0.75], [1.25], [True])
    """
    safe = torch.where(dirs.abs() < 1e-12, torch.full_like(dirs, 1e-12), dirs)
    t0 = (-half_extent - origins) / safe
    t1 = (half_extent - origins) / safe
    t_enter = torch.minimum(t0, t1).amax(dim=-1).clamp(min=near)
    t_exit = torch.maximum(t0, t1).amin(dim=-1).clamp(max=far)
    hit = t_exit > t_enter
    t_enter = torch.where(hit, t_enter, torch.full_like(t_enter, far))
    t_exit = torch.where(hit, t_exit, torch.full_like(t_exit, far))
    return t_enter, t_exit, hit
