"""The training loss: L = MSE(coarse) + MSE(fine) + lambda * (CE(coarse) + CE(fine)) (the paper's eq. 6-8), and
the optional terms beyond the paper: class-balanced CE (:func:`class_weights`), mask and depth losses on the
rendered rays (:func:`ray_geometry_loss`), 3D supervision of both fields at points with known occupancy and
affordance (:func:`point_loss`), agreement between the codes of two views of an object (:func:`code_consistency`) and
a surrogate of the labels' intersection over union (:func:`lovasz_softmax`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from affnerf.model.field import PointGeometry
from affnerf.model.raymarch import RayOutputs
from affnerf.train.sampler import PointBatch


def class_weights(counts: torch.Tensor, power: float) -> torch.Tensor:
    """(C,) class weights proportional to frequency^-power from (C,) pixel counts, scaled so that the weighted
    mean over the counted pixels is 1; classes never seen get weight 0. power 0 gives plain cross-entropy, 0.5
    the square root of inverse frequency (thin parts count more without letting one pixel dominate).

    Example:
        >>> [round(w, 3) for w in class_weights(torch.tensor([900.0, 100.0, 0.0]), 0.5).tolist()]
        [0.833, 2.5, 0.0]
    """
    counts = counts.double()
    freq = counts / counts.sum().clamp(min=1.0)
    raw = torch.where(counts > 0, freq.clamp(min=1e-12) ** -power, torch.zeros_like(freq))
    return (raw / (raw * freq).sum().clamp(min=1e-12)).float()


def affordance_nll(
    probs: torch.Tensor, labels: torch.Tensor, eps: float = 1e-7, weight: torch.Tensor | None = None
) -> torch.Tensor:
    """Mean cross-entropy of rendered class distributions (R, C) against labels (R,); with (C,) class weights, the
    weighted mean (sum of w[label] * nll over the sum of w[label]).

    Example:
        >>> round(affordance_nll(torch.tensor([[0.5, 0.5], [1.0, 0.0]]), torch.tensor([1, 0])).item(), 4)
        0.3466
    """
    nll = -torch.log(probs.gather(1, labels[:, None])[:, 0].clamp(min=eps))
    if weight is None:
        return nll.mean()
    w = weight[labels]
    return (w * nll).sum() / w.sum().clamp(min=eps)


def jaccard_steps(truth: torch.Tensor) -> torch.Tensor:
    """(N, K) 0/1 ground truth of K classes, each column in its own order of decreasing error -> (N, K) how much the
    Jaccard loss 1 - |truth ∩ predicted| / |truth ∪ predicted| of each class grows as the samples, in that order,
    are one by one counted as mispredicted: the gradient of the Lovász extension (Berman et al. 2018, Alg. 1).

    Example:
        >>> [round(v, 4) for v in jaccard_steps(torch.tensor([[1.0], [0.0], [1.0]]))[:, 0].tolist()]
        [0.5, 0.1667, 0.3333]
    """
    total = truth.sum(dim=0, keepdim=True)
    intersection = total - truth.cumsum(dim=0)
    union = total + (1.0 - truth).cumsum(dim=0)
    jaccard = 1.0 - intersection / union
    return torch.cat([jaccard[:1], jaccard[1:] - jaccard[:-1]], dim=0)


def lovasz_softmax(probs: torch.Tensor, labels: torch.Tensor) -> torch.Tensor:
    """Lovász-softmax loss (Berman et al. 2018): the convex surrogate of 1 - IoU of each class present in
    ``labels``, averaged over those classes. (N, C) class probabilities, (N,) ids in [0, C) -> 0-d (0 for N = 0).

    Cross-entropy is a mean over samples, so the background's many pixels outweigh a cap's few; this is a mean over
    classes of each class's own intersection over union in the batch, as the mIoU that scores the model is. For
    one-hot probabilities it equals the mean Jaccard loss exactly; in between it follows each class's errors
    sorted from the largest.

    Example:
        >>> round(lovasz_softmax(torch.tensor([[0.5, 0.5], [0.5, 0.5]]), torch.tensor([0, 1])).item(), 4)
        0.5
        >>> lovasz_softmax(torch.tensor([[1.0, 0.0], [0.0, 1.0]]), torch.tensor([0, 1])).item()
        0.0
    """
    if labels.numel() == 0:
        return probs.sum() * 0.0
    present = torch.unique(labels)
    truth = (labels[:, None] == present[None, :]).to(probs.dtype)
    errors, order = torch.sort((truth - probs[:, present]).abs(), dim=0, descending=True)
    return (errors * jaccard_steps(truth.gather(0, order))).sum(dim=0).mean()


def label_lovasz(
    stages: list[RayOutputs],
    labels: torch.Tensor,
    fields: list[PointGeometry] | None = None,
    point_labels: torch.Tensor | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """:func:`lovasz_softmax` of the rendered rays' class probabilities against their (R,) labels, summed over the
    stages (coarse, fine), and of the fields' (P, C - 1) object-class logits at the 3D points against their (P,)
    ids (0 = no target, as in :func:`point_affordance_ce`), summed over the fields (0 without points)."""
    rays = torch.stack([lovasz_softmax(stage.affordance, labels) for stage in stages]).sum()
    if fields is None or point_labels is None:
        return rays, rays * 0.0
    keep = point_labels > 0
    objects = [lovasz_softmax(torch.softmax(f.logits[keep], dim=-1), point_labels[keep] - 1) for f in fields]
    return rays, torch.stack(objects).sum()


@dataclass
class LossTerms:
    """The loss and its parts (scalars)."""

    total: torch.Tensor
    mse_coarse: torch.Tensor
    mse_fine: torch.Tensor
    ce_coarse: torch.Tensor
    ce_fine: torch.Tensor


def nerf_loss(
    coarse: RayOutputs,
    fine: RayOutputs | None,
    rgb: torch.Tensor,
    labels: torch.Tensor,
    weight: float,
    class_weight: torch.Tensor | None = None,
) -> LossTerms:
    """Photometric MSE plus ``weight`` times affordance cross-entropy (class-weighted when given), over the coarse
    and fine renders."""
    mse_c = torch.mean((coarse.rgb - rgb) ** 2)
    ce_c = affordance_nll(coarse.affordance, labels, weight=class_weight)
    if fine is None:
        zero = torch.zeros((), device=rgb.device)
        return LossTerms(mse_c + weight * ce_c, mse_c, zero, ce_c, zero)
    mse_f = torch.mean((fine.rgb - rgb) ** 2)
    ce_f = affordance_nll(fine.affordance, labels, weight=class_weight)
    return LossTerms(mse_c + mse_f + weight * (ce_c + ce_f), mse_c, mse_f, ce_c, ce_f)


def mask_bce(opacity: torch.Tensor, on_object: torch.Tensor, eps: float = 1e-5) -> torch.Tensor:
    """Mean binary cross-entropy of (R,) rendered opacities against (R,) bool object masks.

    Example:
        >>> round(mask_bce(torch.tensor([0.5, 0.5]), torch.tensor([True, False])).item(), 4)
        0.6931
    """
    o = opacity.clamp(eps, 1.0 - eps)
    return -torch.where(on_object, torch.log(o), torch.log1p(-o)).mean()


def depth_l1(depth: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Mean |rendered - true| z-depth (m) over the rays that meet a surface (target > 0); (R,) each. The rendered
    depth is the weights' sum of sample depths, so a ray that stays transparent is pulled towards opacity too.

    Example:
        >>> round(depth_l1(torch.tensor([0.5, 0.2, 0.0]), torch.tensor([0.4, 0.0, 0.1])).item(), 4)
        0.1
    """
    hit = target > 0
    if not bool(hit.any()):
        return depth.sum() * 0.0
    return (depth[hit] - target[hit]).abs().mean()


def termination_l1(weights: torch.Tensor, t: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Mean over the rays that meet a surface (target > 0) of Σ_k w_k |t_k - target|: how far, in metres, the ray's
    rendering weight lies from the true surface. (R, S) weights and sample depths, (R,) target z-depths.

    Unlike :func:`depth_l1` it cannot be lowered by adding weight: a transparent ray scores 0 and any weight off
    the surface costs, so it moves density onto the surface without thickening outlines (DS-NeRF's idea of
    supervising where a ray terminates, as an L1).

    Example:
        >>> w = torch.tensor([[0.5, 0.5], [1.0, 0.0], [0.0, 1.0]])
        >>> t = torch.tensor([[0.4, 0.6], [0.4, 0.6], [0.4, 0.6]])
        >>> round(termination_l1(w, t, torch.tensor([0.4, 0.4, 0.0])).item(), 4)
        0.05
    """
    hit = target > 0
    if not bool(hit.any()):
        return weights.sum() * 0.0
    return (weights[hit] * (t[hit] - target[hit, None]).abs()).sum(dim=-1).mean()


@dataclass
class RayGeometryTerms:
    """Mask, depth and termination losses of the rendered rays: ``total`` is weighted and summed over the stages;
    the others are the finest stage's (logged)."""

    total: torch.Tensor
    mask: torch.Tensor
    depth: torch.Tensor
    termination: torch.Tensor


def ray_geometry_loss(
    stages: list[RayOutputs], labels: torch.Tensor, depth: torch.Tensor, weights: tuple[float, float, float]
) -> RayGeometryTerms:
    """With ``weights`` (mask, depth, termination): mask * BCE(opacity, label > 0) + depth * L1 depth +
    termination * :func:`termination_l1`, over each stage (coarse, then fine), with (R,) label and z-depth targets
    (DS-NeRF and pixelNeRF-style geometry cues the dataset provides)."""
    masks = torch.stack([mask_bce(s.opacity, labels > 0) for s in stages])
    depths = torch.stack([depth_l1(s.depth, depth) for s in stages])
    ends = torch.stack([termination_l1(s.weights, s.t, depth) for s in stages])
    total = weights[0] * masks.sum() + weights[1] * depths.sum() + weights[2] * ends.sum()
    return RayGeometryTerms(total, masks[-1], depths[-1], ends[-1])


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


def point_affordance_ce(
    logits: torch.Tensor, labels: torch.Tensor, class_weight: torch.Tensor | None = None
) -> torch.Tensor:
    """Mean cross-entropy of (P, C - 1) object-class logits against (P,) affordance ids; id 0 means no target
    (the field predicts classes 1 to C - 1), and no point with a target gives 0.

    Example:
        >>> round(point_affordance_ce(torch.tensor([[2.0, 0.0], [0.0, 0.0]]), torch.tensor([1, 0])).item(), 4)
        0.1269
    """
    keep = labels > 0
    if not bool(keep.any()):
        return logits.sum() * 0.0
    weight = None if class_weight is None else class_weight[1:]
    return torch.nn.functional.cross_entropy(logits[keep], labels[keep] - 1, weight=weight)


def truncated_distance_l1(distance: torch.Tensor, target: torch.Tensor, truncation: float) -> torch.Tensor:
    """Mean |clamp(d) - clamp(d*)| / truncation of (P,) predicted and true signed distances, both clamped to
    +-``truncation`` (DeepSDF's clamped L1): a point farther out than the truncation only asks the field to say
    so, and the loss is in units of the truncation.

    Example:
        >>> round(truncated_distance_l1(torch.tensor([0.01, 0.2, -0.02]), torch.tensor([0.0, 0.05, -0.01]),
        ...                             0.05).item(), 4)
        0.1333
    """
    d = distance.clamp(-truncation, truncation)
    return (d - target.to(d.dtype).clamp(-truncation, truncation)).abs().mean() / truncation


@dataclass
class PointTerms:
    """The 3D supervision and its parts (scalars), each summed over the fields (coarse and fine).

    Attributes:
        total: points_weight * (occupancy + point_affordance_weight * affordance + point_distance_weight *
            distance).
        occupancy: occupancy BCE of each field, summed; affordance: the points' affordance CE, summed; distance:
            the truncated distance L1 of each signed-distance field, summed (0 without one).
        occupancy_last, affordance_last, distance_last: the finest field's terms (logged, like ``loss/mse``).
    """

    total: torch.Tensor
    occupancy: torch.Tensor
    affordance: torch.Tensor
    distance: torch.Tensor
    occupancy_last: torch.Tensor
    affordance_last: torch.Tensor
    distance_last: torch.Tensor


@dataclass(frozen=True)
class PointWeights:
    """Weights and constants of :func:`point_loss`: the term's weight mu, the affordance CE's and the distance
    L1's relative to the occupancy BCE, the occupancy slab (m), the distance truncation (m) and optional (C,)
    class weights of the CE."""

    weight: float
    affordance: float
    distance: float
    slab: float
    truncation: float
    class_weight: torch.Tensor | None = None


def point_loss(fields: list[PointGeometry], targets: PointBatch, w: PointWeights) -> PointTerms:
    """3D supervision of each field's (P,) density, (P, C - 1) logits and, for a signed-distance field, (P,)
    distance against the targets of the step's points (occupancy, labels, truncated signed distance)."""
    occ = [occupancy_bce(f.density, targets.occupancy, w.slab) for f in fields]
    ce = [point_affordance_ce(f.logits, targets.labels, w.class_weight) for f in fields]
    zero = occ[-1] * 0.0
    dist = [
        zero if f.distance is None else truncated_distance_l1(f.distance, targets.distance, w.truncation)
        for f in fields
    ]
    occ_sum, ce_sum, dist_sum = torch.stack(occ).sum(), torch.stack(ce).sum(), torch.stack(dist).sum()
    total = w.weight * (occ_sum + w.affordance * ce_sum + w.distance * dist_sum)
    return PointTerms(total, occ_sum, ce_sum, dist_sum, occ[-1], ce[-1], dist[-1])


def code_consistency(first: torch.Tensor, second: torch.Tensor, eps: float = 1e-8) -> torch.Tensor:
    """How far apart two views' codes of the same objects are, relative to how far apart the objects are: the mean
    of ||first_b − second_b||² over the B objects divided by the mean squared distance of ``first``'s codes from
    their batch mean (a constant: no gradient), so shrinking every code does not lower it. (B, D) and (B, D) -> 0-d.
    B must be at least 2."""
    gap = (first - second).pow(2).sum(-1).mean()
    spread = (first - first.mean(0)).pow(2).sum(-1).mean().detach()
    return gap / (spread + eps)
