"""Input jitter: random changes to the encoders' crops during training, so a photo's lighting, white balance,
focus, noise or an imperfect crop does not change the codes much.

The jitter touches only what the encoders see; the rays keep their true targets. Each crop draws its own colour
change (brightness, per-channel gain, contrast, saturation, gamma) applied to the object's pixels only, a change of
scale and offset of the object in the crop (the crop's intrinsics follow, so pixel-aligned models still project
correctly), a Gaussian blur and pixel noise. ``strength`` scales every range: 0 leaves the crops untouched, 1 is
the default range documented at :func:`jitter_crops`.
"""

from __future__ import annotations

import torch


def _uniform(generator: torch.Generator, n: int, half_width: float, center: float = 1.0) -> torch.Tensor:
    """(n,) uniform draws in [center - half_width, center + half_width]."""
    return center + half_width * (2.0 * torch.rand(n, generator=generator) - 1.0)


def object_mask(images: torch.Tensor, background: torch.Tensor, tol: float = 2.0 / 255.0) -> torch.Tensor:
    """(N, 1, S, S) 1 where a pixel differs from its crop's (N, 3) background colour by more than ``tol``."""
    return ((images - background[:, :, None, None]).abs().amax(dim=1, keepdim=True) > tol).to(images.dtype)


def jitter_colour(images: torch.Tensor, mask: torch.Tensor, strength: float, g: torch.Generator) -> torch.Tensor:
    """(N, 3, S, S) crops with each object's colours changed: brightness x U(1 -/+ 0.4s), per-channel gain
    x U(1 -/+ 0.1s), contrast about the object's mean x U(1 -/+ 0.3s), saturation x U(1 -/+ 0.3s) and gamma
    exp(U(-/+ 0.3s)); background pixels (mask 0) are kept."""
    n = images.shape[0]
    dev = images.device
    gain = (_uniform(g, n, 0.4 * strength)[:, None] * _uniform(g, 3 * n, 0.1 * strength).reshape(n, 3)).to(dev)
    x = images * gain[:, :, None, None]
    area = mask.sum(dim=(2, 3)).clamp(min=1.0)
    mean = (x * mask).sum(dim=(2, 3)) / area
    x = (x - mean[:, :, None, None]) * _uniform(g, n, 0.3 * strength).to(dev)[:, None, None, None] + mean[
        :, :, None, None
    ]
    gray = x.mean(dim=1, keepdim=True)
    x = gray + (x - gray) * _uniform(g, n, 0.3 * strength).to(dev)[:, None, None, None]
    gamma = torch.exp(_uniform(g, n, 0.3 * strength, 0.0)).to(dev)[:, None, None, None]
    x = x.clamp(0.0, 1.0) ** gamma
    return mask * x + (1.0 - mask) * images


def jitter_framing(
    images: torch.Tensor, intrinsics: torch.Tensor, background: torch.Tensor, strength: float, g: torch.Generator
) -> tuple[torch.Tensor, torch.Tensor]:
    """Rescale the object in each crop by U(1 -/+ 0.15s) about the centre and shift it by U(-/+ 0.08s) of the
    crop's side, filling uncovered pixels with the background.

    Args:
        images: (N, 3, S, S); intrinsics: (N, 4) fl_x, fl_y, cx, cy of each crop; background: (N, 3).

    Returns:
        The (N, 3, S, S) crops and their (N, 4) intrinsics after the change (u' = z (u - S/2) + S/2 + t).
    """
    n, _, s, _ = images.shape
    zoom = _uniform(g, n, 0.15 * strength)
    shift = _uniform(g, 2 * n, 0.08 * strength, 0.0).reshape(n, 2)  # fraction of the side
    theta = torch.zeros(n, 2, 3)
    theta[:, 0, 0] = theta[:, 1, 1] = 1.0 / zoom
    theta[:, :, 2] = -2.0 * shift / zoom[:, None]
    grid = torch.nn.functional.affine_grid(theta.to(images), list(images.shape), align_corners=False)
    bg = background[:, :, None, None]
    out = torch.nn.functional.grid_sample(images - bg, grid, align_corners=False) + bg
    z, t = zoom.to(intrinsics)[:, None], (shift * s).to(intrinsics)
    k = torch.cat([intrinsics[:, :2] * z, (intrinsics[:, 2:] - s / 2.0) * z + s / 2.0 + t], dim=1)
    return out, k


def gaussian_blur(images: torch.Tensor, sigma: torch.Tensor, taps: int = 5) -> torch.Tensor:
    """(N, 3, S, S) crops blurred by a separable Gaussian of (N,) standard deviations in pixels (0 = unchanged).

    Example:
        >>> x = torch.zeros(1, 3, 5, 5); x[0, :, 2, 2] = 1.0
        >>> y = gaussian_blur(x, torch.tensor([1.0]))
        >>> round(y.sum().item(), 3), bool(y[0, 0, 2, 2] < 1.0)
        (3.0, True)
    """
    n, c, h, w = images.shape
    offsets = torch.arange(taps, dtype=images.dtype, device=images.device) - taps // 2
    s = sigma.to(images).clamp(min=1e-3)[:, None]
    kernel = torch.exp(-0.5 * (offsets[None] / s) ** 2)
    kernel = (kernel / kernel.sum(dim=1, keepdim=True)).repeat_interleave(c, dim=0)  # (N * C, taps)
    x = images.reshape(1, n * c, h, w)
    pad = taps // 2
    x = torch.nn.functional.pad(x, (pad, pad, 0, 0), mode="replicate")
    x = torch.nn.functional.conv2d(x, kernel[:, None, None, :], groups=n * c)
    x = torch.nn.functional.pad(x, (0, 0, pad, pad), mode="replicate")
    x = torch.nn.functional.conv2d(x, kernel[:, None, :, None], groups=n * c)
    return x.reshape(n, c, h, w)


def blur_and_noise(images: torch.Tensor, strength: float, g: torch.Generator) -> torch.Tensor:
    """(N, 3, H, W) images in [0, 1] blurred (sigma U(0, 1.2s) px on half of them) then noised (Gaussian, sigma
    U(0, 0.03s)), clamped to [0, 1]."""
    n = images.shape[0]
    sigma = torch.rand(n, generator=g) * 1.2 * strength * (torch.rand(n, generator=g) < 0.5)
    x = gaussian_blur(images, sigma)
    noise = torch.randn(x.shape, generator=g) * (torch.rand(n, generator=g) * 0.03 * strength)[:, None, None, None]
    return (x + noise.to(x)).clamp(0.0, 1.0)


def jitter_crops(
    images: torch.Tensor, intrinsics: torch.Tensor, background: torch.Tensor, strength: float, g: torch.Generator
) -> tuple[torch.Tensor, torch.Tensor]:
    """Jitter encoder crops (see the module docstring): colour, then framing, then blur (sigma U(0, 1.2s) px on
    half the crops), then Gaussian noise (sigma U(0, 0.03s)).

    Args:
        images: (B, V, 3, S, S) crops in [0, 1]; intrinsics: (B, V, 4); background: (B, 3) each object's
            background colour; strength: scale of every range (0: returned unchanged); g: CPU random source.

    Returns:
        (B, V, 3, S, S) crops in [0, 1] and their (B, V, 4) intrinsics.
    """
    if strength <= 0:
        return images, intrinsics
    b, v = images.shape[:2]
    x = images.reshape(b * v, *images.shape[2:])
    bg = background.to(x).repeat_interleave(v, dim=0)
    x = jitter_colour(x, object_mask(x, bg), strength, g)
    x, k = jitter_framing(x, intrinsics.reshape(b * v, 4), bg, strength, g)
    x = blur_and_noise(x, strength, g)
    return x.reshape(images.shape), k.reshape(b, v, 4)
