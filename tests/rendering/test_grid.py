"""Occupancy grids and sampling inside occupied cells."""

from __future__ import annotations

import math

import numpy as np
import torch

from affnerf.predict.mesh import extract_labelled_mesh
from affnerf.rendering.grid import OccupancyGrid, build_grid, occupied_samples


def _ball(radius: float):
    return lambda p: 100.0 * (p.norm(dim=-1) < radius).float()


def test_grid_marks_the_ball_and_dilation_grows_it():
    grid = build_grid(_ball(0.1), 0.25, resolution=50, dilation=0)
    share = grid.occupied.float().mean().item()
    assert abs(share - (4 / 3 * math.pi * 0.1**3) / 0.5**3) < 0.01
    grown = build_grid(_ball(0.1), 0.25, resolution=50, dilation=1)
    assert grown.occupied.sum() > grid.occupied.sum() and bool((grown.occupied | ~grid.occupied).all())
    assert grid.lookup(torch.tensor([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [0.0, 0.0, 0.9]])).tolist() == [
        True,
        False,
        False,
    ]


def test_samples_fall_in_occupied_cells_and_stand_for_the_occupied_length():
    grid = build_grid(_ball(0.1), 0.25, resolution=64, dilation=0)
    origins = torch.tensor([[0.0, 0.0, 1.0], [0.3, 0.0, 1.0]])
    dirs = torch.tensor([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])
    near, far = torch.tensor([0.75, 0.75]), torch.tensor([1.25, 1.25])
    t, step, hit = occupied_samples(grid, origins, dirs, near, far, num=16, candidates=256)
    assert hit.tolist() == [True, False]
    z = 1.0 - t[0]
    cell = 0.5 / 64
    assert torch.all(z.abs() < 0.1 + cell)  # inside the ball's chord, to within a cell
    assert torch.all(t[0, 1:] >= t[0, :-1])
    assert abs(step[0].item() * 16 - 0.2) < 2 * cell  # 16 samples stand for the 0.2 m chord


def test_mesh_from_the_grid_matches_the_full_evaluation():
    smooth = lambda p: 100.0 * torch.clamp((0.12 - p.norm(dim=-1)) / 0.01 + 0.5, 0.0, 1.0)  # noqa: E731
    labels = lambda p: torch.ones(len(p), dtype=torch.long)  # noqa: E731
    full = extract_labelled_mesh(smooth, labels, resolution=48, level=50.0, half_extent=0.25)
    grid = build_grid(smooth, 0.25, resolution=24, threshold=1.0)
    fast = extract_labelled_mesh(smooth, labels, resolution=48, level=50.0, half_extent=0.25, occupancy=grid)
    np.testing.assert_allclose(np.sort(fast.vertices, axis=0), np.sort(full.vertices, axis=0), atol=1e-6)
    assert isinstance(grid, OccupancyGrid)
