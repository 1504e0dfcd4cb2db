"""Occupancy grids for empty-space skipping at inference (the fast path of issue 6).

Once an object is encoded its field no longer changes, so its density can be evaluated once on a coarse grid
over the scene cube. Rays then place their samples only inside occupied cells: a few candidate positions
per cell along the ray are checked against the grid, and the samples are spread over the occupied stretches by
inverse transform sampling. Rays that cross no occupied cell render background without evaluating the field.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import torch
import torch.nn.functional as F


@dataclass
class OccupancyGrid:
    """A boolean occupancy grid over the cube [-half_extent, half_extent]^3.

    Attributes:
        occupied: (R, R, R) bool indexed [x, y, z].
        half_extent: half the cube's side.
    """

    occupied: torch.Tensor
    half_extent: float

    @property
    def resolution(self) -> int:
        return self.occupied.shape[0]

    def lookup(self, points: torch.Tensor) -> torch.Tensor:
        """(N,) whether (N, 3) points fall in occupied cells (points outside the cube are empty), on the points'
        device (a grid built on a GPU also answers for points on the CPU, as mesh extraction makes them)."""
        r = self.resolution
        idx = torch.floor((points + self.half_extent) / (2 * self.half_extent) * r).long()
        inside = ((idx >= 0) & (idx < r)).all(dim=-1)
        idx = idx.clamp(0, r - 1)
        return inside & self.occupied.to(idx.device)[idx[:, 0], idx[:, 1], idx[:, 2]]


@torch.no_grad()
def build_grid(
    density: Callable[[torch.Tensor], torch.Tensor],
    half_extent: float,
    resolution: int = 64,
    threshold: float = 1.0,
    dilation: int = 1,
    chunk: int | None = None,
    device: torch.device | str = "cpu",
) -> OccupancyGrid:
    """Evaluate ``density`` at the cell centres of the cube [-half_extent, half_extent]^3 and mark cells above
    ``threshold``, grown by ``dilation`` cells (so thin structures between cell centres are not lost).

    Args:
        density: (N, 3) points -> (N,) densities.
        half_extent: half the cube's side, metres.
        resolution: cells per side.
        threshold: density above which a cell is occupied.
        dilation: cells by which the occupied region grows.
        chunk: points per call of ``density`` (None: all in one call).
        device: where the grid lives.
    """
    cell = 2 * half_extent / resolution
    axis = torch.linspace(-half_extent + cell / 2, half_extent - cell / 2, resolution, device=device)
    xs, ys, zs = torch.meshgrid(axis, axis, axis, indexing="ij")
    points = torch.stack([xs.reshape(-1), ys.reshape(-1), zs.reshape(-1)], dim=-1)
    step = chunk or len(points)
    values = torch.cat([density(points[s : s + step]) for s in range(0, len(points), step)])
    occupied = (values > threshold).reshape(resolution, resolution, resolution)
    if dilation > 0:
        k = 2 * dilation + 1
        occupied = F.max_pool3d(occupied[None, None].float(), k, stride=1, padding=dilation)[0, 0] > 0
    return OccupancyGrid(occupied, half_extent)


def occupied_samples(
    grid: OccupancyGrid,
    origins: torch.Tensor,
    dirs: torch.Tensor,
    near: torch.Tensor,
    far: torch.Tensor,
    num: int,
    candidates: int,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Samples spread over the occupied stretches of each ray.

    Args:
        grid: the object's occupancy.
        origins: (R, 3).
        dirs: (R, 3).
        near: (R,) start of each ray's range.
        far: (R,) end of each ray's range.
        num: samples per ray.
        candidates: evenly spaced positions per ray checked against the grid.

    Returns:
        t (R, num) increasing samples, the length each sample stands for (R,) (the occupied length over ``num``,
        so empty gaps between occupied stretches add no opacity), and hit (R,) whether the ray crosses any
        occupied cell.
    """
    steps = (torch.arange(candidates, device=origins.device, dtype=origins.dtype) + 0.5) / candidates
    t_cand = near[:, None] + (far - near)[:, None] * steps  # (R, C) cell-ish centres along the ray
    pts = origins[:, None, :] + t_cand[..., None] * dirs[:, None, :]
    occ = grid.lookup(pts.reshape(-1, 3)).reshape(t_cand.shape).to(origins.dtype)
    hit = occ.sum(dim=-1) > 0
    # inverse transform sampling over the occupied candidate bins (each bin one candidate spacing wide)
    width = (far - near)[:, None] / candidates
    cdf = torch.cumsum(occ, dim=-1)
    total = cdf[:, -1:].clamp(min=1e-9)
    u = (torch.arange(num, device=origins.device, dtype=origins.dtype) + 0.5) / num * total
    idx = torch.searchsorted(cdf.contiguous(), u.contiguous(), right=True).clamp(max=candidates - 1)
    before = torch.where(idx > 0, cdf.gather(1, (idx - 1).clamp(min=0)), torch.zeros_like(u))
    frac = (u - before).clamp(0, 1)
    t = near[:, None] + width * (idx.to(origins.dtype) + frac)
    return t, width[:, 0] * total[:, 0] / num, hit
