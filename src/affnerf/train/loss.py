"""The training loss: L = MSE(coarse) + MSE(fine) + lambda * (CE(coarse) + CE(fine)) (the paper's eq. 6-8)."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from affnerf.model.raymarch import RayOutputs


def affordance_nll(probs: torch.Tensor, labels: torch.Tensor, eps: float = 1e-7) -> torch.Tensor:
    """Mean cross-entropy of rendered class distributions (R, C) against labels (R,).

    Example:
        >>> round(affordance_nll(torch.tensor([[0.5, 0.5], [1.0, 0.0]]), torch.tensor([1, 0])).item(), 4)
        0.3466
    """
    picked = probs.gather(1, labels[:, None])[:, 0]
    return -torch.log(picked.clamp(min=eps)).mean()


@dataclass
class LossTerms:
    """The loss and its parts (scalars)."""

    total: torch.Tensor
    mse_coarse: torch.Tensor
    mse_fine: torch.Tensor
    ce_coarse: torch.Tensor
    ce_fine: torch.Tensor


def nerf_loss(
    coarse: RayOutputs, fine: RayOutputs | None, rgb: torch.Tensor, labels: torch.Tensor, weight: float
) -> LossTerms:
    """Photometric MSE plus ``weight`` times affordance cross-entropy, over the coarse and fine renders."""
    mse_c = torch.mean((coarse.rgb - rgb) ** 2)
    ce_c = affordance_nll(coarse.affordance, labels)
    if fine is None:
        zero = torch.zeros((), device=rgb.device)
        return LossTerms(mse_c + weight * ce_c, mse_c, zero, ce_c, zero)
    mse_f = torch.mean((fine.rgb - rgb) ** 2)
    ce_f = affordance_nll(fine.affordance, labels)
    return LossTerms(mse_c + mse_f + weight * (ce_c + ce_f), mse_c, mse_f, ce_c, ce_f)
