"""Input jitter of the encoders' crops (affnerf.train.augment)."""

from __future__ import annotations

import torch

from affnerf.train.augment import gaussian_blur, jitter_crops, jitter_framing, object_mask


def _crops(b: int = 2, v: int = 1, s: int = 32) -> torch.Tensor:
    images = torch.ones(b, v, 3, s, s)
    images[..., 12:20, 10:22] = torch.tensor([0.8, 0.2, 0.1])[:, None, None]  # an orange box on white
    return images


def test_strength_zero_returns_the_crops_untouched():
    images, k = _crops(), torch.rand(2, 1, 4)
    out, k2 = jitter_crops(images, k, torch.ones(2, 3), 0.0, torch.Generator().manual_seed(0))
    assert out is images and k2 is k


def test_jitter_changes_the_object_keeps_range_and_is_reproducible():
    images, k, bg = _crops(), torch.tensor([[[40.0, 40.0, 16.0, 16.0]]] * 2), torch.ones(2, 3)
    a, ka = jitter_crops(images, k, bg, 1.0, torch.Generator().manual_seed(3))
    b, kb = jitter_crops(images, k, bg, 1.0, torch.Generator().manual_seed(3))
    torch.testing.assert_close(a, b)
    torch.testing.assert_close(ka, kb)
    assert a.shape == images.shape and ka.shape == k.shape
    assert float(a.min()) >= 0.0 and float(a.max()) <= 1.0
    assert not torch.allclose(a, images)


def test_colour_jitter_leaves_the_background_alone():
    images = _crops()[:, 0]
    mask = object_mask(images, torch.ones(2, 3))
    assert int(mask.sum()) == 2 * 8 * 12
    from affnerf.train.augment import jitter_colour

    out = jitter_colour(images, mask, 1.0, torch.Generator().manual_seed(1))
    torch.testing.assert_close(out * (1 - mask), images * (1 - mask))


def test_framing_moves_the_object_and_its_intrinsics_together():
    """A point's pixel under the new intrinsics lands where the jittered crop shows it."""
    s = 32
    images = torch.ones(1, 3, s, s)
    images[0, :, 15:17, 15:17] = 0.0  # a dark dot at pixel centre (16, 16)
    k = torch.tensor([[40.0, 40.0, 16.0, 16.0]])  # the dot is the projection of a point on the optical axis
    g = torch.Generator().manual_seed(5)
    out, k2 = jitter_framing(images, k, torch.ones(1, 3), 1.0, g)
    dark = (out[0, 0] < 0.5).nonzero().float()
    centre = dark.mean(0) + 0.5  # (row, col) in pixel units, cell centres at +0.5
    assert abs(float(centre[1]) - float(k2[0, 2])) < 0.75 and abs(float(centre[0]) - float(k2[0, 3])) < 0.75
    assert not torch.allclose(k2, k)


def test_blur_keeps_the_mean_and_spreads_a_dot():
    x = torch.zeros(2, 3, 9, 9)
    x[:, :, 4, 4] = 1.0
    y = gaussian_blur(x, torch.tensor([0.0, 1.0]))
    torch.testing.assert_close(y[0], x[0], atol=1e-5, rtol=0)  # sigma 0: unchanged
    assert float(y[1, 0, 4, 4]) < 0.5 and abs(float(y[1].sum()) - 3.0) < 1e-4
