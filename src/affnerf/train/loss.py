"""The training loss: L = MSE(coarse) + MSE(fine) + lambda * (CE(coarse) + CE(fine)) (the paper's eq. 6-8), and the
optional 3D supervision of both fields at points with known occupancy and affordance (:func:`point_loss`)."""

from __future__ import annotations

import math
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


def occupancy_slab(surface_density: float) -> float:
    """The slab thickness (m) whose opacity is 0.5 at ``surface_density`` (per metre): ln 2 / surface_density.

    Example:
        >>> round(occupancy_slab(50.0), 5)
        0.01386
    """
    return math.log(2.0) / surface_density


def occupancy_bce(density: torch.Tensor, occupancy: torch.Tensor, slab: float, eps: float = 1e-6) -> torch.Tensor:
    """Mean binary cross-entropy of the occupancy 1 - exp(-density * slab) against (P,) 0/1 targets.

    The occupancy of a point is the opacity of a slab of thickness ``slab`` at its density, the quantity volume
    rendering composites (UNISURF renders occupancy as alpha in the same way). With ``slab`` = ln 2 /
    ``surface_density``, the classifier's 0.5 boundary is the density level that meshes are extracted at, so the
    supervised surface is the extracted one. Outside, the loss is density * slab, an L1 penalty on density in free
    space with a constant gradient; inside, -log(1 - exp(-density * slab)) falls towards 0 as density grows, so
    opaque interiors are not pushed to infinity. A logistic of density would need a scale and bias of its own
    and would not mean opacity. Written with ``expm1`` for accuracy at small densities.

    Args:
        density: (P,) non-negative densities (per metre); occupancy: (P,) targets; slab: metres.

    Example:
        >>> d = torch.tensor([0.0, 50.0, 50.0])
        >>> [round(v, 4) for v in [occupancy_bce(d[1:2], torch.ones(1), 0.01).item(),
        ...                        occupancy_bce(d[2:], torch.zeros(1), 0.01).item()]]
        [0.9328, 0.5]
    """
    x = density * slab
    target = occupancy.to(x.dtype)
    inside = -torch.log((-torch.expm1(-x)).clamp(min=eps))
    return (target * inside + (1.0 - target) * x).mean()


def point_affordance_ce(logits: torch.Tensor, labels: torch.Tensor) -> torch.Tensor:
    """Mean cross-entropy of (P, C - 1) object-class logits against (P,) affordance ids; id 0 means no target
    (the field predicts classes 1 to C - 1), and no point with a target gives 0.

    Example:
        >>> round(point_affordance_ce(torch.tensor([[2.0, 0.0], [0.0, 0.0]]), torch.tensor([1, 0])).item(), 4)
        0.1269
    """
    keep = labels > 0
    if not bool(keep.any()):
        return logits.sum() * 0.0
    return torch.nn.functional.cross_entropy(logits[keep], labels[keep] - 1)


@dataclass
class PointTerms:
    """The 3D supervision and its parts (scalars), each summed over the fields (coarse and fine).

    Attributes:
        total: points_weight * (occupancy + point_affordance_weight * affordance).
        occupancy: occupancy BCE of each field, summed; affordance: the points' affordance CE, summed.
        occupancy_last, affordance_last: the finest field's terms (logged, like ``loss/mse``).
    """

    total: torch.Tensor
    occupancy: torch.Tensor
    affordance: torch.Tensor
    occupancy_last: torch.Tensor
    affordance_last: torch.Tensor


def point_loss(
    fields: list[tuple[torch.Tensor, torch.Tensor]],
    occupancy: torch.Tensor,
    labels: torch.Tensor,
    slab: float,
    weight: float,
    affordance_weight: float,
) -> PointTerms:
    """3D supervision of each field's (P,) density and (P, C - 1) logits against (P,) occupancy and labels."""
    occ = [occupancy_bce(density, occupancy, slab) for density, _ in fields]
    ce = [point_affordance_ce(logits, labels) for _, logits in fields]
    occ_sum, ce_sum = torch.stack(occ).sum(), torch.stack(ce).sum()
    return PointTerms(weight * (occ_sum + affordance_weight * ce_sum), occ_sum, ce_sum, occ[-1], ce[-1])
