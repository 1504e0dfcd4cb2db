"""Semantic-Ray (Liu et al., CVPR 2023), compact: a semantic radiance field from posed source views through
Cross-Reprojection Attention.

Each source view goes through a ResNet18 (the first three stages, upsampled and stacked, as PixelNeRF-M). Every
sample of a ray is projected into every source view, where it reads the view's feature and colour; with the
sample's position in that camera's frame these make one token per (sample, view). Cross-Reprojection Attention
then mixes them in two steps, as the original factorises it: attention along the ray within each view (each
sample attends to the view's other samples of the same ray: where along the ray this view sees surface), then
attention across views (each sample's query, the mean of its view tokens, attends to the views). The result, with
the source colours blended by the cross-view attention weights, conditions the same density, colour and semantic
(affordance) field as PixelNeRF-M; the semantic logits are volume-rendered like the colour, and training uses the
photometric + semantic loss of every model here.

Shrunk from the original (NeuRay backbone, 4 heads, stacked transformer layers, a semantic ray aggregation
network): one single-head attention layer each way on ``2 * code_dim`` channels, ResNet18 features, PixelNeRF-M's
MLP field as the density, colour and semantic heads.
"""

from __future__ import annotations

import torch
from torch import nn

from affnerf.model.config import ModelConfig
from affnerf.model.encoding import encoding_dim, positional_encoding
from affnerf.model.multiview import (
    BlockCondition,
    MultiViewNeRF,
    RayBlockRenderer,
    ViewEncoding,
    attend,
    masked_mean,
    per_object,
    sample_views,
    stacked_features,
)

#: Positional-encoding frequencies of a sample's position in a source camera's frame.
VIEW_PE = 6


class CrossReprojectionAttention(nn.Module):
    """Attention along the ray within each view, then across views.

    Args:
        dim: token channels.
    """

    def __init__(self, dim: int) -> None:
        super().__init__()
        self.ray_qkv = nn.Linear(dim, 3 * dim)
        self.ray_out = nn.Linear(dim, dim)
        self.view_q = nn.Linear(dim, dim)
        self.view_k = nn.Linear(dim, dim)
        self.view_v = nn.Linear(dim, dim)
        self.norm_ray = nn.LayerNorm(dim)
        self.norm_view = nn.LayerNorm(dim)

    def along_ray(self, tokens: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
        """Intra-view attention: (R, S, V, D) tokens -> (R, S, V, D); each (ray, view) attends over its S
        samples, the samples outside the view (``valid`` (R, S, V) false) masked."""
        x = tokens.transpose(1, 2)  # (R, V, S, D)
        q, k, v = self.ray_qkv(x).chunk(3, dim=-1)
        out, _ = attend(q, k, v, valid.transpose(1, 2))
        return self.norm_ray(x + self.ray_out(out)).transpose(1, 2)

    def across_views(self, tokens: torch.Tensor, valid: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Cross-view attention: (R, S, V, D) tokens -> (R, S, D) per-sample features and (R, S, V) view weights;
        each sample's query is the mean of its valid view tokens."""
        mean = masked_mean(tokens, valid, dim=2)  # (R, S, D)
        out, weights = attend(self.view_q(mean)[..., None, :], self.view_k(tokens), self.view_v(tokens), valid)
        return self.norm_view(mean + out[..., 0, :]), weights[..., 0, :]

    def forward(self, tokens: torch.Tensor, valid: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(R, S, V, D) tokens and (R, S, V) validity -> (R, S, D) features and (R, S, V) view weights."""
        return self.across_views(self.along_ray(tokens, valid), valid)


class SemanticRay(MultiViewNeRF):
    """Cross-Reprojection Attention over posed source views conditioning a density, colour and semantic field.

    Args:
        config: architecture and sampling (``encoder_width``, ``code_dim``, field sizes).
        num_classes: affordance classes including background.
    """

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        dim = 2 * config.code_dim
        self.dim = dim
        feat = sum(self.backbone.channels)
        self.token = nn.Sequential(nn.Linear(feat + 3 + encoding_dim(3, VIEW_PE), dim), nn.ReLU(), nn.Linear(dim, dim))
        self.cra = CrossReprojectionAttention(dim)
        self.renderer = RayBlockRenderer(config, num_classes, dim, dim + 3)

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> ViewEncoding:
        """Feature maps of (B, V, 3, S, S) crops, with the crops and their cameras."""
        b, v = images.shape[:2]
        stacked = stacked_features(self.backbone, images.reshape(b * v, *images.shape[2:]))
        return ViewEncoding(
            features=stacked.reshape(b, v, *stacked.shape[1:]),
            images=images,
            intrinsics=intrinsics,
            world_to_camera=torch.linalg.inv(poses),
            size=images.shape[-1],
        )

    def tokens(self, encoding: ViewEncoding, b: int, points: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """Object b's (r, S, 3) samples in its V views: (r, S, V, D) tokens, (r, S, V, 3) source colours and
        (r, S, V) validity."""
        r, s = points.shape[:2]
        flat = points.reshape(-1, 3)
        w2c, k = encoding.world_to_camera[b], encoding.intrinsics[b]
        feats, cams, valid = sample_views(flat, encoding.features[b], w2c, k, encoding.size)
        colours, _, _ = sample_views(flat, encoding.images[b], w2c, k, encoding.size)
        tokens = self.token(torch.cat([feats, colours, positional_encoding(cams, VIEW_PE)], dim=-1))
        v = feats.shape[1]
        return tokens.reshape(r, s, v, -1), colours.reshape(r, s, v, 3), valid.reshape(r, s, v)

    def ray_condition(self, encoding: ViewEncoding, ray_object: torch.Tensor) -> BlockCondition:
        """Each ray's samples: Cross-Reprojection Attention features (trunk), and those features with the source
        colours blended by the cross-view weights (colour head)."""

        def one(b: int, points: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            tokens, colours, valid = self.tokens(encoding, b, points)
            feature, weights = self.cra(tokens, valid)
            blend = (weights[..., None] * colours).sum(2)
            return feature, torch.cat([feature, blend], dim=-1)

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            return per_object(ray_object, rays, points, (self.dim, self.dim + 3), one)

        return cond
