"""The volume rendering quadrature: weights from densities, and their accumulation of colour, depth, opacity and
affordance probabilities (NeRF eq. 3, Semantic-NeRF's semantic rendering)."""

from __future__ import annotations

import torch


def sample_deltas(t: torch.Tensor, far: torch.Tensor) -> torch.Tensor:
    """Distances between consecutive samples; the last sample's interval runs to ``far``.

    Args:
        t: (R, S) increasing sample positions.
        far: (R,) end of each ray's interval.

    Returns:
        (R, S) non-negative lengths.

    Example:
        >>> sample_deltas(torch.tensor([[0.5, 1.0, 2.0]]), torch.tensor([3.0])).tolist()
        [[0.5, 1.0, 1.0]]
    """
    return torch.cat([t[:, 1:] - t[:, :-1], (far[:, None] - t[:, -1:]).clamp(min=0.0)], dim=-1)


def weights_from_density(sigma: torch.Tensor, deltas: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Rendering weights w_k = T_k (1 - exp(-sigma_k delta_k)) with T_k = exp(-sum_{j<k} sigma_j delta_j).

    Args:
        sigma: (R, S) non-negative densities.
        deltas: (R, S) interval lengths.

    Returns:
        weights (R, S) and the transmittance left after the last sample (R,), so that
        ``weights.sum(-1) + transmittance == 1``.

    Example:
        >>> w, t = weights_from_density(torch.tensor([[0.0, 1e9, 5.0]]), torch.ones(1, 3))
        >>> w.tolist(), t.tolist()
        ([[0.0, 1.0, 0.0]], [0.0])
    """
    tau = sigma * deltas
    cum = torch.cumsum(tau, dim=-1)
    trans_before = torch.exp(-torch.cat([torch.zeros_like(cum[:, :1]), cum[:, :-1]], dim=-1))
    alpha = 1.0 - torch.exp(-tau)
    return trans_before * alpha, torch.exp(-cum[:, -1])


def accumulate(weights: torch.Tensor, values: torch.Tensor) -> torch.Tensor:
    """Weighted sum along each ray: (R, S) weights and (R, S, C) values -> (R, C).

    Example:
        >>> accumulate(torch.tensor([[0.25, 0.5]]), torch.tensor([[[1.0], [3.0]]])).tolist()
        [[1.75]]
    """
    return torch.einsum("rs,rsc->rc", weights, values)


def render_depth(weights: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
    """Expected ray parameter of the surface (R,), unnormalised: sum_k w_k t_k (0 for an empty ray)."""
    return (weights * t).sum(dim=-1)


def composite(color: torch.Tensor, opacity: torch.Tensor, background: torch.Tensor) -> torch.Tensor:
    """Put the background behind accumulated colour: (R, 3) + (1 - opacity (R,)) * background (3,) -> (R, 3)."""
    return color + (1.0 - opacity)[:, None] * background


def render_affordance(weights: torch.Tensor, probs: torch.Tensor, transmittance: torch.Tensor) -> torch.Tensor:
    """Per-pixel affordance distribution including the background class.

    The field gives each sample a distribution over the object classes 1..C-1; the pixel's distribution is their
    weighted sum, and whatever light passes through the object (the transmittance) is background, class 0.

    Args:
        weights: (R, S).
        probs: (R, S, C - 1) per-sample class probabilities over object classes.
        transmittance: (R,) light left after the last sample.

    Returns:
        (R, C) probabilities that sum to 1.

    Example:
        >>> w, t = weights_from_density(torch.tensor([[1e9]]), torch.ones(1, 1))
        >>> render_affordance(w, torch.tensor([[[0.25, 0.75]]]), t).tolist()
        [[0.0, 0.25, 0.75]]
    """
    return torch.cat([transmittance[:, None], accumulate(weights, probs)], dim=-1)
