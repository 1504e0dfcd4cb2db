"""The AFF-NeRF model: image -> (shape code, appearance code); rays + codes -> colour, depth, affordance."""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from affnerf.model.config import ModelConfig
from affnerf.model.field import ConditionalField
from affnerf.model.resnet import CodeEncoder
from affnerf.objects.asset import CANONICAL_HALF_EXTENT
from affnerf.rendering.rays import intersect_aabb
from affnerf.rendering.samplers import merge_samples, pdf_samples, stratified_samples
from affnerf.rendering.volume import (
    accumulate,
    composite,
    render_affordance,
    render_depth,
    sample_deltas,
    weights_from_density,
)


@dataclass
class RayOutputs:
    """What one stage (coarse or fine) renders for R rays.

    Attributes:
        rgb: (R, 3) colour over the background.
        depth: (R,) expected z-depth where the ray is opaque (weights-averaged, 0 for empty rays).
        opacity: (R,) accumulated opacity.
        affordance: (R, C) class probabilities, class 0 background.
        t: (R, S) sample positions.
        weights: (R, S) rendering weights.
    """

    rgb: torch.Tensor
    depth: torch.Tensor
    opacity: torch.Tensor
    affordance: torch.Tensor
    t: torch.Tensor
    weights: torch.Tensor


@dataclass
class Codes:
    """Shape and appearance codes of B objects, each (B, code_dim)."""

    shape: torch.Tensor
    appearance: torch.Tensor


class AffNeRF(nn.Module):
    """Two ResNet18 encoders and a coarse and a fine conditional field.

    Args:
        config: architecture and sampling.
        num_classes: affordance classes including background.
    """

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__()
        self.config = config
        self.num_classes = num_classes
        self.shape_encoder = CodeEncoder(config.code_dim, config.encoder_width)
        self.appearance_encoder = CodeEncoder(config.code_dim, config.encoder_width)

        def field() -> ConditionalField:
            return ConditionalField(
                num_classes,
                config.code_dim,
                config.field_width,
                config.field_depth,
                config.color_width,
                config.affordance_width,
                config.pe_xyz,
                config.pe_dir,
            )

        self.coarse = field()
        self.fine = field() if config.num_fine > 0 else None

    def forward(
        self,
        images: torch.Tensor,
        ray_object: torch.Tensor,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        perturb: bool = True,
        generator: torch.Generator | None = None,
    ) -> tuple[RayOutputs, RayOutputs | None]:
        """Encode each object's image and render its rays (one training forward pass; see :meth:`render_rays`).

        Args:
            images: (B, 3, S, S) encoder crops, one per object.
            ray_object: (R,) object index of each ray.
        """
        return self.render_rays(self.encode(images), ray_object, origins, dirs, background, perturb, generator)

    def encode(self, images: torch.Tensor) -> Codes:
        """(B, 3, S, S) object crops in [0, 1] -> their codes."""
        return Codes(self.shape_encoder(images), self.appearance_encoder(images))

    def ray_bounds(self, origins: torch.Tensor, dirs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(R,) start, end and whether each ray is sampled at all."""
        c = self.config
        if c.clip_to_cube:
            return intersect_aabb(origins, dirs, CANONICAL_HALF_EXTENT, c.near, c.far)
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
        codes: Codes,
        ray_object: torch.Tensor,
        background: torch.Tensor,
    ) -> RayOutputs:
        r, s = t.shape
        points = origins[:, None, :] + t[..., None] * dirs[:, None, :]
        unit = dirs / dirs.norm(dim=-1, keepdim=True)
        idx = ray_object[:, None].expand(r, s).reshape(-1)
        out = field(
            points.reshape(-1, 3),
            unit[:, None, :].expand(r, s, 3).reshape(-1, 3),
            codes.shape[idx],
            codes.appearance[idx],
        )
        weights, trans = weights_from_density(out.sigma.reshape(r, s), sample_deltas(t, far))
        opacity = weights.sum(dim=-1)
        color = accumulate(weights, out.rgb.reshape(r, s, 3))
        probs = torch.softmax(out.logits.reshape(r, s, -1), dim=-1)
        return RayOutputs(
            rgb=composite(color, opacity, background),
            depth=render_depth(weights, t),
            opacity=opacity,
            affordance=render_affordance(weights, probs, trans),
            t=t,
            weights=weights,
        )

    def render_rays(
        self,
        codes: Codes,
        ray_object: torch.Tensor,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        perturb: bool = False,
        generator: torch.Generator | None = None,
    ) -> tuple[RayOutputs, RayOutputs | None]:
        """Render rays of several objects, coarse then fine.

        Args:
            codes: codes of B objects.
            ray_object: (R,) index of each ray's object in ``codes``.
            origins: (R, 3) ray origins in the canonical frame.
            dirs: (R, 3) directions with unit length along the camera axis (ray parameter = z-depth).
            background: (R, 3) background colour behind each ray.
            perturb: random sample positions (training) or deterministic ones.
            generator: random source when perturbing.

        Returns:
            The coarse and the fine stage's outputs (fine is None without fine samples). Rays that miss the
            sampled region render background with zero opacity.
        """
        c = self.config
        near, far, hit = self.ray_bounds(origins, dirs)
        t_coarse = stratified_samples(near, far, c.num_coarse, perturb, generator)
        coarse = self._stage(self.coarse, t_coarse, far, origins, dirs, codes, ray_object, background)
        if self.fine is None:
            return _mask_missed(coarse, hit, background), None
        t_fine = merge_samples(t_coarse, pdf_samples(t_coarse, coarse.weights, c.num_fine, perturb, generator))
        fine = self._stage(self.fine, t_fine, far, origins, dirs, codes, ray_object, background)
        return _mask_missed(coarse, hit, background), _mask_missed(fine, hit, background)


def _mask_missed(out: RayOutputs, hit: torch.Tensor, background: torch.Tensor) -> RayOutputs:
    """Rays that never enter the sampled region: background colour, zero opacity, background class."""
    if bool(hit.all()):
        return out
    miss = ~hit
    bg_class = torch.zeros_like(out.affordance)
    bg_class[:, 0] = 1.0
    return RayOutputs(
        rgb=torch.where(miss[:, None], background, out.rgb),
        depth=torch.where(miss, torch.zeros_like(out.depth), out.depth),
        opacity=torch.where(miss, torch.zeros_like(out.opacity), out.opacity),
        affordance=torch.where(miss[:, None], bg_class, out.affordance),
        t=out.t,
        weights=torch.where(miss[:, None], torch.zeros_like(out.weights), out.weights),
    )
