"""Where to evaluate the field along each ray: stratified samples, hierarchical (inverse-CDF) samples and, in
training, samples drawn around the true surface (depth-guided sampling)."""

from __future__ import annotations

from dataclasses import dataclass

import torch


def stratified_samples(
    near: torch.Tensor, far: torch.Tensor, num: int, perturb: bool = True, generator: torch.Generator | None = None
) -> torch.Tensor:
    """Split each ray's [near, far] into ``num`` equal bins and take one point per bin.

    Args:
        near: (R,) start of each ray's interval.
        far: (R,) end of each ray's interval.
        num: samples per ray.
        perturb: a uniformly random point in each bin (training); otherwise the bin centres.
        generator: random source of the perturbation.

    Returns:
        (R, num) increasing ray parameters.

    Example:
        >>> stratified_samples(torch.tensor([0.0]), torch.tensor([1.0]), 4, perturb=False).tolist()
        [[0.125, 0.375, 0.625, 0.875]]
    """
    steps = torch.arange(num, dtype=near.dtype, device=near.device)
    if perturb:
        u = torch.rand((near.shape[0], num), generator=generator, dtype=near.dtype, device="cpu").to(near.device)
    else:
        u = torch.full((near.shape[0], num), 0.5, dtype=near.dtype, device=near.device)
    frac = (steps[None, :] + u) / num
    return near[:, None] + (far - near)[:, None] * frac


def pdf_samples(
    t: torch.Tensor,
    weights: torch.Tensor,
    num: int,
    perturb: bool = True,
    generator: torch.Generator | None = None,
    eps: float = 1e-5,
) -> torch.Tensor:
    """Draw samples from the piecewise-constant density given by coarse weights (NeRF's hierarchical sampling).

    The coarse samples ``t`` are the centres of bins whose edges are the midpoints between neighbours (the first
    and last bins extend by half a spacing); each bin's probability is proportional to its weight plus ``eps``
    (so a ray with no weight still samples uniformly).

    Args:
        t: (R, S) increasing coarse sample positions, S >= 2.
        weights: (R, S) their rendering weights (not differentiated through).
        num: new samples per ray.
        perturb: uniformly random draws (training); otherwise evenly spaced quantiles.
        generator: random source.
        eps: weight added to every bin.

    Returns:
        (R, num) increasing samples, within the bins' span.

    Example:
        >>> t = torch.tensor([[0.5, 1.5, 2.5]])
        >>> pdf_samples(t, torch.tensor([[0.0, 1.0, 0.0]]), 2, perturb=False, eps=0.0).tolist()
        [[1.25, 1.75]]
    """
    weights = weights.detach()
    mid = 0.5 * (t[:, 1:] + t[:, :-1])
    first = t[:, :1] - (mid[:, :1] - t[:, :1])
    last = t[:, -1:] + (t[:, -1:] - mid[:, -1:])
    edges = torch.cat([first, mid, last], dim=-1)  # (R, S + 1)
    w = weights + eps
    pdf = w / w.sum(dim=-1, keepdim=True)
    cdf = torch.cat([torch.zeros_like(pdf[:, :1]), torch.cumsum(pdf, dim=-1)], dim=-1)
    cdf[:, -1] = 1.0
    if perturb:
        u = torch.rand((t.shape[0], num), generator=generator, dtype=t.dtype, device="cpu").to(t.device)
        u, _ = torch.sort(u, dim=-1)
    else:
        u = ((torch.arange(num, dtype=t.dtype, device=t.device) + 0.5) / num).expand(t.shape[0], num)
    u = u.contiguous()
    idx = torch.searchsorted(cdf, u, right=True).clamp(1, cdf.shape[-1] - 1)
    c0, c1 = torch.gather(cdf, 1, idx - 1), torch.gather(cdf, 1, idx)
    e0, e1 = torch.gather(edges, 1, idx - 1), torch.gather(edges, 1, idx)
    denom = torch.where(c1 - c0 < 1e-12, torch.ones_like(c1), c1 - c0)
    return e0 + (u - c0) / denom * (e1 - e0)


def merge_samples(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """(R, Sa + Sb) sorted union of two sets of samples per ray."""
    merged, _ = torch.sort(torch.cat([a, b], dim=-1), dim=-1)
    return merged


@dataclass(frozen=True)
class SurfaceGuide:
    """Where a training step's rays meet the true surface, so that a share of each such ray's fine samples is drawn
    around it instead of from the coarse weights (depth-guided sampling, as DS-NeRF and Dense Depth Priors place
    samples near known depth early in training).

    Attributes:
        depth: (R,) true z-depth of each ray in metres (0 = the ray meets no surface: its samples are not moved).
        share: fraction of a ray's fine samples drawn around the surface, in [0, 1].
        sigma: standard deviation in metres of those draws along the ray.
    """

    depth: torch.Tensor
    share: float
    sigma: float


def surface_samples(
    depth: torch.Tensor,
    near: torch.Tensor,
    far: torch.Tensor,
    num: int,
    sigma: float,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """Draw ``num`` samples per ray from a normal around its true depth, kept inside the ray's interval.

    Args:
        depth: (R,) true z-depth (the ray parameter at the surface).
        near: (R,) start of each ray's interval.
        far: (R,) end of each ray's interval.
        num: samples per ray.
        sigma: standard deviation of the draws, metres (0: every sample at the depth).
        generator: random source.

    Returns:
        (R, num) increasing samples in [near, far].

    Example:
        >>> surface_samples(torch.tensor([0.5, 2.0]), torch.zeros(2), torch.ones(2), 2, 0.0).tolist()
        [[0.5, 0.5], [1.0, 1.0]]
    """
    noise = torch.randn((depth.shape[0], num), generator=generator, dtype=depth.dtype, device="cpu")
    t = depth[:, None] + sigma * noise.to(depth.device)
    t, _ = torch.sort(torch.minimum(torch.maximum(t, near[:, None]), far[:, None]), dim=-1)
    return t


def guided_samples(
    t: torch.Tensor,
    guide: SurfaceGuide,
    near: torch.Tensor,
    far: torch.Tensor,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """Replace the first ``round(guide.share * S)`` of each surface ray's S samples by draws around its depth
    (:func:`surface_samples`); rays that meet no surface (depth 0) keep theirs.

    Args:
        t: (R, S) samples per ray (for example :func:`pdf_samples`'s).
        guide: the rays' true depths, the share and the spread (``depth`` indexed like ``t``'s rays).
        near: (R,) start of each ray's interval.
        far: (R,) end of each ray's interval.
        generator: random source.

    Returns:
        (R, S) samples, increasing along each ray.

    Example:
        >>> t = torch.tensor([[0.125, 0.25, 0.375, 0.5], [0.125, 0.25, 0.375, 0.5]])
        >>> g = SurfaceGuide(torch.tensor([0.75, 0.0]), share=0.5, sigma=0.0)
        >>> guided_samples(t, g, torch.zeros(2), torch.ones(2)).tolist()
        [[0.375, 0.5, 0.75, 0.75], [0.125, 0.25, 0.375, 0.5]]
    """
    k = round(guide.share * t.shape[1])
    if k == 0:
        return t
    drawn = surface_samples(guide.depth, near, far, t.shape[1], guide.sigma, generator)
    moved = (guide.depth > 0)[:, None] & (torch.arange(t.shape[1], device=t.device) < k)[None, :]
    return torch.sort(torch.where(moved, drawn, t), dim=-1).values
