"""Whole-image rays (affnerf.model.views.camera_rays)."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.data.cameras import Intrinsics
from affnerf.model.views import camera_rays


def test_camera_rays_cover_every_pixel_row_by_row_from_the_camera_centre():
    intr = Intrinsics.from_fov(4, 3, np.deg2rad(60.0))
    c2w = np.eye(4)
    c2w[:3, 3] = [0.1, -0.2, 0.7]
    origins, dirs = camera_rays(intr, c2w)
    assert origins.shape == dirs.shape == (12, 3) and origins.dtype == torch.float64
    assert torch.allclose(origins, torch.tensor([0.1, -0.2, 0.7], dtype=torch.float64).expand(12, 3))
    # row by row: the second ray is one pixel to the right of the first, the fifth one pixel below it
    assert dirs[1, 0] > dirs[0, 0] and torch.isclose(dirs[1, 1], dirs[0, 1])
    assert torch.isclose(dirs[4, 0], dirs[0, 0]) and dirs[4, 1] != dirs[0, 1]
