"""Coarse-to-fine volume rendering of a conditioned field, shared by AFF-NeRF and the NeRF baselines.

What conditions the field differs between models (global codes for AFF-NeRF, pixel-aligned features for
PixelNeRF, nothing for a per-object Semantic-NeRF); it is passed in as a callable
``condition(points (N, 3), rays (N,)) -> (trunk input (N, Dt), colour input (N, Dc))``, each a tensor or, for codes
shared by an object's points, a factored :class:`~affnerf.model.field.ObjectCodes`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import torch
from torch import nn

from affnerf.model.config import ModelConfig
from affnerf.model.field import Code, ConditionalField
from affnerf.rendering.grid import OccupancyGrid, occupied_samples
from affnerf.rendering.rays import intersect_aabb
from affnerf.rendering.samplers import (
    SurfaceGuide,
    guided_samples,
    merge_samples,
    pdf_samples,
    stratified_samples,
)
from affnerf.rendering.volume import (
    accumulate,
    composite,
    render_affordance,
    render_depth,
    sample_deltas,
    weights_from_density,
)

Condition = Callable[[torch.Tensor, torch.Tensor], tuple[Code, Code]]


@dataclass
class RayOutputs:
    """What one stage (coarse or fine) renders for R rays.

    Attributes:
        rgb: (R, 3) colour over the background.
        depth: (R,) sum of weights times sample depth (divide by opacity for the surface depth).
        opacity: (R,) accumulated opacity.
        affordance: (R, C) class probabilities, class 0 background.
        t: (R, S) sample positions (empty rays: zeros).
        weights: (R, S) rendering weights.
    """

    rgb: torch.Tensor
    depth: torch.Tensor
    opacity: torch.Tensor
    affordance: torch.Tensor
    t: torch.Tensor
    weights: torch.Tensor


def scatter_rays(out: RayOutputs, hit: torch.Tensor, background: torch.Tensor) -> RayOutputs:
    """Outputs of all R rays from those of the rays that were rendered (``hit``); the others are background
    with zero opacity and the background class."""
    if bool(hit.all()):
        return out
    n, s = hit.shape[0], out.t.shape[1]

    def full(values: torch.Tensor, fill: torch.Tensor) -> torch.Tensor:
        result = fill.clone()
        result[hit] = values
        return result

    bg_class = torch.zeros((n, out.affordance.shape[1]), dtype=out.affordance.dtype, device=hit.device)
    bg_class[:, 0] = 1.0
    zeros = torch.zeros(n, dtype=out.depth.dtype, device=hit.device)
    zeros_s = torch.zeros((n, s), dtype=out.t.dtype, device=hit.device)
    return RayOutputs(
        rgb=full(out.rgb, background.to(out.rgb.dtype)),
        depth=full(out.depth, zeros),
        opacity=full(out.opacity, zeros),
        affordance=full(out.affordance, bg_class),
        t=full(out.t, zeros_s),
        weights=full(out.weights, zeros_s),
    )


class FieldRenderer(nn.Module):
    """A coarse and a fine conditioned field and their coarse-to-fine rendering (one field for both passes with
    ``coarse_field`` ``shared``: ``coarse`` is then the only field, and ``fine`` None).

    Args:
        config: field sizes and sampling.
        num_classes: affordance classes including background.
        trunk_cond_dim: size of the per-point input joining PE(position).
        color_cond_dim: size of the per-point input joining PE(direction) in the colour head.
    """

    def __init__(self, config: ModelConfig, num_classes: int, trunk_cond_dim: int, color_cond_dim: int) -> None:
        super().__init__()
        self.config = config

        def field() -> ConditionalField:
            return ConditionalField(
                num_classes,
                trunk_cond_dim,
                config.field_width,
                config.field_depth,
                config.color_width,
                config.affordance_width,
                config.pe_xyz,
                config.pe_dir,
                color_code_dim=color_cond_dim,
                film=config.conditioning == "film",
                sdf=config.geometry == "sdf",
            )

        self.coarse = field()
        self.fine = field() if config.num_fine > 0 and config.coarse_field == "own" else None
        self.points_evaluated = 0  # field evaluations so far (for benchmarks)

    def ray_bounds(self, origins: torch.Tensor, dirs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(R,) start, end, and whether each ray is sampled at all (the cube clip, or the full range)."""
        c = self.config
        if c.clip_to_cube:
            return intersect_aabb(origins, dirs, c.scene_half_extent, c.near, c.far)
        n = origins.shape[0]
        near = torch.full((n,), c.near, dtype=origins.dtype, device=origins.device)
        return near, torch.full_like(near, c.far), torch.ones(n, dtype=torch.bool, device=origins.device)

    def _stage(
        self,
        field: ConditionalField,
        t: torch.Tensor,
        far: torch.Tensor,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        rays: torch.Tensor,
        condition: Condition,
        background: torch.Tensor,
        deltas: torch.Tensor | None = None,
    ) -> RayOutputs:
        r, s = t.shape
        points = (origins[:, None, :] + t[..., None] * dirs[:, None, :]).reshape(-1, 3)
        unit = dirs / dirs.norm(dim=-1, keepdim=True)
        ray_of_point = rays[:, None].expand(r, s).reshape(-1)
        self.points_evaluated += len(points)
        trunk_in, color_in = condition(points, ray_of_point)
        out = field(points, unit[:, None, :].expand(r, s, 3).reshape(-1, 3), trunk_in, color_in)
        deltas = sample_deltas(t, far) if deltas is None else deltas
        weights, trans = weights_from_density(out.sigma.reshape(r, s), deltas)
        opacity = weights.sum(dim=-1)
        probs = torch.softmax(out.logits.reshape(r, s, out.logits.shape[-1]), dim=-1)
        return RayOutputs(
            rgb=composite(accumulate(weights, out.rgb.reshape(r, s, 3)), opacity, background),
            depth=render_depth(weights, t),
            opacity=opacity,
            affordance=render_affordance(weights, probs, trans),
            t=t,
            weights=weights,
        )

    def render_rays_in_grid(
        self,
        condition: Condition,
        grid: OccupancyGrid,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        num: int = 32,
        candidates: int = 128,
    ) -> RayOutputs:
        """Inference fast path: ``num`` samples per ray spread over the occupied cells of ``grid``, evaluated by
        the fine field only (the coarse field without one); rays crossing no occupied cell render background
        without evaluating the field."""
        near, far, inside = intersect_aabb(origins, dirs, grid.half_extent, self.config.near, self.config.far)
        t, step, hit = occupied_samples(grid, origins, dirs, near, far, num, candidates)
        hit = hit & inside
        idx = torch.nonzero(hit, as_tuple=True)[0]
        field = self.fine_field()
        deltas = step[idx, None].expand(len(idx), num)
        out = self._stage(field, t[idx], far[idx], origins[idx], dirs[idx], idx, condition, background[idx], deltas)
        return scatter_rays(out, hit, background)

    def render_rays(
        self,
        condition: Condition,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        perturb: bool = False,
        generator: torch.Generator | None = None,
        guide: SurfaceGuide | None = None,
    ) -> tuple[RayOutputs, RayOutputs | None]:
        """Render R rays, coarse then fine; only rays that cross the sampled region evaluate the field.

        Args:
            condition: per-point conditioning (see the module docstring); ``rays`` index the R rays.
            origins: (R, 3) ray origins in the canonical frame.
            dirs: (R, 3) directions with unit length along the camera axis (ray parameter = z-depth).
            background: (R, 3) colour behind each ray.
            perturb: random sample positions (training) or deterministic ones.
            generator: random source when perturbing.
            guide: training only: the R rays' true depths, so a share of each surface ray's fine samples is drawn
                around its surface (:func:`~affnerf.rendering.samplers.guided_samples`); None: all from the
                coarse weights. No effect without fine samples.

        Returns:
            The coarse and the fine stage's outputs for all R rays (fine is None without fine samples; the coarse
            one carries no gradient with ``coarse_field`` ``shared``, :meth:`coarse_gradients`).
        """
        c = self.config
        near, far, hit = self.ray_bounds(origins, dirs)
        idx = torch.nonzero(hit, as_tuple=True)[0]
        o, d, bg, n_, f_ = origins[idx], dirs[idx], background[idx], near[idx], far[idx]
        t_coarse = stratified_samples(n_, f_, c.num_coarse, perturb, generator)
        with self.coarse_gradients():
            coarse = self._stage(self.coarse, t_coarse, f_, o, d, idx, condition, bg)
        if c.num_fine == 0:
            return scatter_rays(coarse, hit, background), None
        t_drawn = pdf_samples(t_coarse, coarse.weights, c.num_fine, perturb, generator)
        if guide is not None:
            t_drawn = guided_samples(t_drawn, replace(guide, depth=guide.depth[idx]), n_, f_, generator)
        fine = self._stage(self.fine_field(), merge_samples(t_coarse, t_drawn), f_, o, d, idx, condition, bg)
        return scatter_rays(coarse, hit, background), scatter_rays(fine, hit, background)

    def coarse_gradients(self) -> torch.autograd.grad_mode.set_grad_enabled:
        """The gradient mode of the coarse stage: as around it, or off with ``coarse_field`` ``shared`` and fine
        samples to place (the one field's coarse outputs only place them; losses on them are constants)."""
        shared = self.config.coarse_field == "shared" and self.config.num_fine > 0
        return torch.set_grad_enabled(torch.is_grad_enabled() and not shared)

    def fine_field(self) -> ConditionalField:
        """The field of the fine pass, meshes and fast rendering: the fine one, or the only one (a coarse-only
        model, or one whose coarse pass uses the fine field, ``coarse_field`` ``shared``)."""
        return self.fine if self.fine is not None else self.coarse
