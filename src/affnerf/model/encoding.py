"""Positional encoding (NeRF): a point and its sines and cosines at octave frequencies."""

from __future__ import annotations

import math

import torch


def positional_encoding(x: torch.Tensor, num_freqs: int, include_input: bool = True) -> torch.Tensor:
    """Encode (..., D) coordinates as (..., D * (2 * num_freqs + include_input)).

    The k-th frequency is 2^k * pi, k = 0..num_freqs-1; output is [x, sin(f0 x), cos(f0 x), sin(f1 x), ...].

    Example:
        >>> positional_encoding(torch.tensor([[0.5, 0.0]]), 1).round(decimals=3).tolist()
        [[0.5, 0.0, 1.0, 0.0, -0.0, 1.0]]
    """
    freqs = (2.0 ** torch.arange(num_freqs, dtype=x.dtype, device=x.device)) * math.pi
    angles = x[..., None, :] * freqs[:, None]  # (..., F, D)
    enc = torch.stack([torch.sin(angles), torch.cos(angles)], dim=-2).flatten(-3)
    return torch.cat([x, enc], dim=-1) if include_input else enc


def encoding_dim(dim: int, num_freqs: int, include_input: bool = True) -> int:
    """Size of :func:`positional_encoding`'s output for ``dim`` inputs."""
    return dim * (2 * num_freqs + int(include_input))
