"""Rays in torch follow the same convention as the dataset renderer."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.data.cameras import Intrinsics, look_at, world_rays
from affnerf.rendering.rays import intersect_aabb, pixel_rays


def test_pixel_rays_match_the_renderer_rays():
    intr = Intrinsics(40, 30, 35.0, 36.0, 20.5, 14.0)
    c2w = look_at(np.array([0.3, -0.5, 0.4]), np.zeros(3))
    origins, dirs = world_rays(intr, c2w)
    vv, uu = np.mgrid[0:30, 0:40]
    pix = torch.tensor(np.stack([uu.ravel(), vv.ravel()], 1))
    o, d = pixel_rays(pix, torch.tensor([35.0, 36.0, 20.5, 14.0], dtype=torch.float64), torch.tensor(c2w))
    np.testing.assert_allclose(o.numpy(), origins, atol=1e-12)
    np.testing.assert_allclose(d.numpy(), dirs, atol=1e-12)


def test_cube_clipping():
    o = torch.tensor([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.3]])
    d = torch.tensor([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -2.0]])
    tn, tf, hit = intersect_aabb(o, d, 0.25, 0.1, 1.5)
    assert hit.tolist() == [True, False, True, True]
    torch.testing.assert_close(tn, torch.tensor([0.75, 1.5, 0.1, 0.1]))  # inside the cube: starts at near
    torch.testing.assert_close(tf, torch.tensor([1.25, 1.5, 0.25, 0.275]))
