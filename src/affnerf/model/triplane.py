"""Triplane conditioning (beyond the paper): the shape code decoded into three axis-aligned feature planes.

The paper's field takes the 32-d shape code as one more input of its MLP, so every detail of an object's shape
must be computed from the code at every point by that small network. Here a 2D convolutional generator turns each
object's code once into three feature planes over the canonical cube (xy, xz, yz; as EG3D's generator and
Convolutional Occupancy Networks' decoder), and a point reads its features bilinearly from the three planes: local
detail (a handle, a blade) lives in the planes and the field's MLP only has to decode it. The generator runs once
per object and the plane reads are cheap. The trunk takes the reads beside the code itself (global facts, such as
which part is which, need not be written into every texel; planes alone learned the affordance more slowly,
benchmarks/results/triplane.md). The code keeps its size, so encoders, the test-time fit and retrieval work
unchanged.
"""

from __future__ import annotations

import itertools
import math

import torch
from torch import nn
from torch.nn import functional as F

#: Side of the generator's first feature map.
START_RESOLUTION = 4


def plane_coordinates(points: torch.Tensor, half_extent: float) -> torch.Tensor:
    """(N, 3) canonical positions -> (3, N, 2) their coordinates in the xy, xz and yz planes, in [-1, 1] over the
    cube [-half_extent, half_extent]^3 (``grid_sample``'s convention: first coordinate along the plane's width).

    Example:
        >>> plane_coordinates(torch.tensor([[0.1, -0.2, 0.3]]), 0.4)[:, 0].tolist()
        [[0.25, -0.5], [0.25, 0.75], [-0.5, 0.75]]
    """
    u = points / half_extent
    return torch.stack([u[:, [0, 1]], u[:, [0, 2]], u[:, [1, 2]]])


def sample_planes(planes: torch.Tensor, points: torch.Tensor, half_extent: float) -> torch.Tensor:
    """Bilinear read of one object's (3, C, R, R) planes at (N, 3) canonical points -> (N, 3C) features, the three
    planes' features side by side (points outside the cube read the planes' border)."""
    grid = plane_coordinates(points, half_extent)[:, None]  # (3, 1, N, 2)
    feats = F.grid_sample(planes, grid, mode="bilinear", padding_mode="border", align_corners=False)  # (3, C, 1, N)
    return feats[:, :, 0].permute(2, 0, 1).reshape(len(points), -1)


def generator_widths(resolution: int, base: int) -> list[int]:
    """Channel widths of the generator's feature maps from :data:`START_RESOLUTION` up to ``resolution``: ``base``,
    halved at every second upsampling, never below 16.

    Example:
        >>> generator_widths(64, 64)
        [64, 64, 32, 32, 16]
    """
    steps = math.log2(resolution / START_RESOLUTION)
    if resolution < START_RESOLUTION or steps != int(steps):
        raise ValueError(f"plane resolution must be {START_RESOLUTION} times a power of two, not {resolution}")
    return [max(16, base >> (i // 2)) for i in range(int(steps) + 1)]


class PlaneGenerator(nn.Module):
    """Codes -> triplanes: a linear map to a 4 x 4 feature map, then (bilinear x2 upsampling, 3 x 3 convolution,
    leaky ReLU) until ``resolution``, and a 1 x 1 convolution to three planes of ``channels`` features.

    Args:
        code_dim: size of the shape code.
        channels: features per plane.
        resolution: side of each plane (4 times a power of two).
        base: channels of the first feature map.
    """

    def __init__(self, code_dim: int, channels: int, resolution: int, base: int = 64) -> None:
        super().__init__()
        widths = generator_widths(resolution, base)
        self.channels, self.resolution = channels, resolution
        self.stem = nn.Linear(code_dim, widths[0] * START_RESOLUTION**2)
        self.blocks = nn.ModuleList(nn.Conv2d(a, b, 3, padding=1) for a, b in itertools.pairwise(widths))
        self.head = nn.Conv2d(widths[-1], 3 * channels, 1)

    def forward(self, codes: torch.Tensor) -> torch.Tensor:
        """(B, code_dim) codes -> (B, 3, channels, R, R) planes."""
        b = codes.shape[0]
        h = F.leaky_relu(self.stem(codes), 0.2).reshape(b, -1, START_RESOLUTION, START_RESOLUTION)
        for conv in self.blocks:
            h = F.interpolate(h, scale_factor=2.0, mode="bilinear", align_corners=False)
            h = F.leaky_relu(conv(h), 0.2)
        return self.head(h).reshape(b, 3, self.channels, self.resolution, self.resolution)
