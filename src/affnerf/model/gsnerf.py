"""GSNeRF (Chou et al., CVPR 2024), compact: a Semantic Geo-Reasoner predicts every source view's depth from a
multi-view cost volume together with semantic features, and rendering is guided by those depths.

**Semantic Geo-Reasoner.** Each source view's crop goes through a ResNet18 (three stages, stacked as in
PixelNeRF-M). Taking each source view in turn as the reference, a plane sweep places ``DEPTH_PLANES`` fronto-
parallel planes across the scene cube in front of it, warps every view's (reduced) features onto each plane and
keeps their variance across views (MVSNet's cost); a small 3D convolution turns it into a cost per plane and
pixel, and the depth is its soft-argmin (the expectation of the plane depths under softmax(-cost)). A 2D
convolution of the view's features and its depth-probability volume gives its semantic features.

**Depth-guided rendering.** The coarse samples are stratified; the fine ones lie in a band of ``DEPTH_BAND``
around each ray's predicted depth (the coarse sample whose depth in the source views best matches the views'
predicted depths), merged with the coarse ones. Each sample, projected into the source views, makes one token
per view from the view's features, semantic features, colour, and its depth relative to the view's predicted
depth (which also gives GeoNeRF's occlusion mask: a view sees the sample when it is not behind the view's surface);
a mean-and-variance token joins them, and attention across the views and a convolution along the ray
(GeoNeRF's along-ray aggregation) make the sample's feature. The field (density, colour, semantic heads) is
PixelNeRF-M's, with the source colours blended by the attention weights joining the colour head.

**Losses.** The photometric and semantic loss of every model here. GSNeRF also supervises depth: the Geo-Reasoner's
predicted depth of every source view is supervised with the true depth at the crop's pixels
(:meth:`GSNeRF.auxiliary_losses`, ``loss/source_depth``, L1 in metres weighted by :data:`SOURCE_DEPTH_WEIGHT`),
as the original supervises its depth estimates when depth is known; the trainer's ``--depth-weight`` can add an L1
loss on the rendered z-depth too (off in the ``small`` recipe, as for the other models).

Shrunk from the original (GeoNeRF's three-level cascaded cost volumes of 8 views, a semantic segmentation
decoder, 4-layer transformers): one cost volume of ``DEPTH_PLANES`` planes at 1/4 of the crop per source view,
one attention layer, a one-layer along-ray convolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional as F

from affnerf.model.config import ModelConfig
from affnerf.model.encoding import encoding_dim, positional_encoding
from affnerf.model.multiview import (
    BlockCondition,
    FineSampler,
    MultiViewNeRF,
    RayBlockRenderer,
    ViewEncoding,
    attend,
    depth_band_samples,
    masked_mean,
    per_object,
    sample_views,
    stacked_features,
)
from affnerf.model.pixelnerf import project

#: Depth planes of each source view's cost volume.
DEPTH_PLANES = 16
#: Weight of the Geo-Reasoner's source-view depth loss (L1 in metres) beside the photometric and semantic losses.
SOURCE_DEPTH_WEIGHT = 1.0
#: Channels of the features the plane sweep compares.
COST_CHANNELS = 8
#: Half-width (m) of the band of fine samples around a ray's predicted depth, and the depth (m) behind a view's
#: predicted surface beyond which that view no longer sees a sample.
DEPTH_BAND = 0.03
#: Positional-encoding frequencies of a sample's position in a source camera's frame.
VIEW_PE = 4


@dataclass
class GeoEncoding(ViewEncoding):
    """:class:`ViewEncoding` plus the Geo-Reasoner's outputs.

    Attributes:
        semantic: (B, V, Cs, h, w) semantic feature maps.
        depth: (B, V, h, w) predicted z-depth (m) of every source view.
    """

    semantic: torch.Tensor
    depth: torch.Tensor


def pixel_points(intrinsics: torch.Tensor, c2w: torch.Tensor, depths: torch.Tensor, h: int, w: int, size: int):
    """World points (D, h, w, 3) of an h x w grid of pixel centres over a camera's S x S crop at z-depths (D,)."""
    k = intrinsics
    step = size / w
    u = (torch.arange(w, dtype=depths.dtype, device=depths.device) + 0.5) * step
    v = (torch.arange(h, dtype=depths.dtype, device=depths.device) + 0.5) * (size / h)
    x = (u[None, :] - k[2]) / k[0]
    y = -(v[:, None] - k[3]) / k[1]
    rays = torch.stack([x.expand(h, w), y.expand(h, w), -torch.ones_like(x.expand(h, w))], dim=-1)
    cam = depths[:, None, None, None] * rays  # (D, h, w, 3), z = -depth
    return cam @ c2w[:3, :3].T + c2w[:3, 3]


def plane_sweep_variance(
    features: torch.Tensor,
    intrinsics: torch.Tensor,
    c2w: torch.Tensor,
    ref: int,
    depths: torch.Tensor,
    size: int,
) -> torch.Tensor:
    """The cost volume of view ``ref``: at each of its pixels and depth planes, the variance across the V views
    of their features at that point (MVSNet's variance metric).

    Args:
        features: (V, C, h, w) feature maps over each view's S x S crop.
        intrinsics: (V, 4) crop intrinsics; c2w: (V, 4, 4) camera-to-world poses.
        ref: the reference view; depths: (D,) z-depths of its planes; size: the crop side S.

    Returns:
        (C, D, h, w) variances (zero where every view shows the same feature).
    """
    _, c, h, w = features.shape
    points = pixel_points(intrinsics[ref], c2w[ref], depths, h, w, size).reshape(-1, 3)
    w2c = torch.linalg.inv(c2w)
    warped = []
    for v in range(features.shape[0]):
        _, pix = project(points, w2c[v], intrinsics[v])
        grid = (pix / size * 2.0 - 1.0)[None, :, None, :]
        warped.append(F.grid_sample(features[v][None], grid, padding_mode="border", align_corners=False)[0, :, :, 0])
    stack = torch.stack(warped)  # (V, C, D h w)
    var = stack.var(dim=0, unbiased=False)
    return var.reshape(c, len(depths), h, w)


def soft_argmin(cost: torch.Tensor, depths: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Depth regression from a (..., D, h, w) cost: the expected depth under p = softmax(-cost) over the planes.

    Args:
        cost: (..., D, h, w) cost per plane and pixel; depths: (..., D) the planes' z-depths.

    Returns:
        (..., h, w) depths and (..., D, h, w) probabilities.

    Example:
        >>> z, _ = soft_argmin(torch.tensor([0.0, 0.0])[:, None, None], torch.tensor([1.0, 2.0]))
        >>> z.tolist()
        [[1.5]]
    """
    prob = torch.softmax(-cost, dim=-3)
    return (prob * depths[..., None, None]).sum(-3), prob


def depth_planes(c2w: torch.Tensor, half_extent: float, near: float, num: int = DEPTH_PLANES) -> torch.Tensor:
    """(num,) z-depths spanning the scene cube seen from a camera (its distance to the origin ± the cube's
    half-diagonal, not nearer than ``near``)."""
    dist = c2w[:3, 3].norm()
    reach = math.sqrt(3.0) * half_extent
    lo = torch.clamp(dist - reach, min=near)
    return lo + (dist + reach - lo) * torch.linspace(0.0, 1.0, num, dtype=c2w.dtype, device=c2w.device)


class GeoReasoner(nn.Module):
    """Per-view depth from a plane-sweep cost volume, and semantic features, from stacked feature maps.

    Args:
        feat_dim: channels of the feature maps; sem_dim: semantic feature channels.
    """

    def __init__(self, feat_dim: int, sem_dim: int) -> None:
        super().__init__()
        self.reduce = nn.Conv2d(feat_dim, COST_CHANNELS, 1)
        self.regularise = nn.Sequential(
            nn.Conv3d(COST_CHANNELS, 8, 3, padding=1), nn.ReLU(), nn.Conv3d(8, 1, 3, padding=1)
        )
        self.semantic = nn.Sequential(
            nn.Conv2d(feat_dim + DEPTH_PLANES, sem_dim, 3, padding=1), nn.ReLU(), nn.Conv2d(sem_dim, sem_dim, 1)
        )

    def forward(
        self,
        features: torch.Tensor,
        intrinsics: torch.Tensor,
        c2w: torch.Tensor,
        size: int,
        bounds: tuple[float, float],
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """One object's (V, C, h, w) features, (V, 4) crop intrinsics and (V, 4, 4) poses -> (V, h, w) depths and
        (V, Cs, h, w) semantic features; ``bounds`` is (scene half-extent, nearest depth), both m."""
        reduced = self.reduce(features)
        volumes, planes = [], []
        for ref in range(features.shape[0]):
            planes.append(depth_planes(c2w[ref], *bounds))
            volumes.append(plane_sweep_variance(reduced, intrinsics, c2w, ref, planes[-1], size))
        cost = self.regularise(torch.stack(volumes))[:, 0]  # (V, D, h, w)
        depth, prob = soft_argmin(cost, torch.stack(planes))
        return depth, self.semantic(torch.cat([features, prob], dim=1))


class GSNeRF(MultiViewNeRF):
    """Semantic Geo-Reasoner and depth-guided, attention-aggregated rendering (see the module docstring).

    Args:
        config: architecture and sampling (``encoder_width``, ``code_dim``, field sizes).
        num_classes: affordance classes including background.
    """

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        feat = sum(self.backbone.channels)
        dim = 2 * config.code_dim
        self.dim = dim
        self.reasoner = GeoReasoner(feat, config.code_dim)
        token_in = feat + config.code_dim + 3 + 1 + encoding_dim(3, VIEW_PE)
        self.token = nn.Sequential(nn.Linear(token_in, dim), nn.ReLU(), nn.Linear(dim, dim))
        self.global_token = nn.Linear(2 * dim, dim)
        self.qkv = nn.Linear(dim, 3 * dim)
        self.norm = nn.LayerNorm(dim)
        self.along_ray = nn.Conv1d(dim, dim, 3, padding=1)
        self.renderer = RayBlockRenderer(config, num_classes, dim, dim + 3)

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> GeoEncoding:
        """Feature maps, predicted depths and semantic features of (B, V, 3, S, S) crops, with their cameras."""
        b, v = images.shape[:2]
        stacked = stacked_features(self.backbone, images.reshape(b * v, *images.shape[2:]))
        features = stacked.reshape(b, v, *stacked.shape[1:])
        size = images.shape[-1]
        bounds = (self.config.scene_half_extent, self.config.near)
        geo = [self.reasoner(features[i], intrinsics[i], poses[i], size, bounds) for i in range(b)]
        return GeoEncoding(
            features=features,
            images=images,
            intrinsics=intrinsics,
            world_to_camera=torch.linalg.inv(poses),
            size=size,
            semantic=torch.stack([g[1] for g in geo]),
            depth=torch.stack([g[0] for g in geo]),
        )

    def relative_depth(self, encoding: GeoEncoding, b: int, flat: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """Object b's (N, 3) points in its V views: (N, V) depth relative to the view's predicted depth (m; > 0
        behind it), (N, V, 3) camera-frame positions and (N, V) validity."""
        w2c, k, size = encoding.world_to_camera[b], encoding.intrinsics[b], encoding.size
        predicted, cams, valid = sample_views(flat, encoding.depth[b][:, None], w2c, k, size)
        return -cams[..., 2] - predicted[..., 0], cams, valid

    def view_samples(self, encoding: GeoEncoding, b: int, flat: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """Object b's (N, 3) points in its V views: (N, V, C + Cs + 3) features, semantic features and colours,
        then :meth:`relative_depth`'s three outputs."""
        w2c, k, size = encoding.world_to_camera[b], encoding.intrinsics[b], encoding.size
        maps = torch.cat([encoding.features[b], encoding.semantic[b]], dim=1)
        feats, _, _ = sample_views(flat, maps, w2c, k, size)
        colours, _, _ = sample_views(flat, encoding.images[b], w2c, k, size)
        return torch.cat([feats, colours], dim=-1), *self.relative_depth(encoding, b, flat)

    def aggregate(self, tokens: torch.Tensor, visible: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(N, V, D) view tokens and (N, V) visibility -> (N, D) features (the mean-and-variance token after
        attention across the views and it) and (N, V) its attention weights over the views."""
        mean = masked_mean(tokens, visible, dim=1)
        var = masked_mean((tokens - mean[:, None]) ** 2, visible, dim=1)
        all_tokens = torch.cat([tokens, self.global_token(torch.cat([mean, var], -1))[:, None]], dim=1)
        mask = torch.cat([visible, torch.ones_like(visible[:, :1])], dim=1)
        q, k, v = self.qkv(all_tokens).chunk(3, dim=-1)
        out, weights = attend(q[:, -1:], k, v, mask)
        feature = self.norm(all_tokens[:, -1] + out[:, 0])
        view_w = weights[:, 0, :-1]
        return feature, view_w / view_w.sum(-1, keepdim=True).clamp(min=1e-8)

    def ray_condition(self, encoding: GeoEncoding, ray_object: torch.Tensor) -> BlockCondition:
        """Each ray's samples: attention-aggregated source-view tokens, then a convolution along the ray (trunk);
        those features with the attention-blended source colours (colour head)."""

        def one(b: int, points: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            r, s = points.shape[:2]
            feats, relative, cams, valid = self.view_samples(encoding, b, points.reshape(-1, 3))
            visible = valid & (relative < DEPTH_BAND)
            rel = torch.tanh(relative / DEPTH_BAND)[..., None]
            tokens = self.token(torch.cat([feats, rel, positional_encoding(cams, VIEW_PE)], dim=-1))
            feature, weights = self.aggregate(tokens, visible)
            blend = (weights[..., None] * feats[..., -3:]).sum(1).reshape(r, s, 3)
            feature = feature.reshape(r, s, -1)
            feature = feature + torch.relu(self.along_ray(feature.transpose(1, 2))).transpose(1, 2)
            return feature, torch.cat([feature, blend], dim=-1)

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            return per_object(ray_object, rays, points, (self.dim, self.dim + 3), one)

        return cond

    def ray_depth(self, encoding: GeoEncoding, b: int, points: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """(r,) predicted depth of object b's rays from their (r, S, 3) samples at depths (r, S): the sample whose
        depth in the views that see it is closest to their predicted depths (mean absolute difference)."""
        relative, _, valid = self.relative_depth(encoding, b, points.reshape(-1, 3))
        valid = valid.reshape(*t.shape, -1)
        err = (relative.reshape(valid.shape).abs() * valid).sum(-1) / valid.sum(-1).clamp(min=1)
        err = torch.where(valid.any(-1), err, torch.full_like(err, float("inf")))
        return t.gather(1, err.argmin(dim=1, keepdim=True))[:, 0]

    def fine_sampler(self, encoding: GeoEncoding, ray_object: torch.Tensor) -> FineSampler:
        """Depth-guided fine samples: ``num_fine`` stratified in [t* - DEPTH_BAND, t* + DEPTH_BAND] around each
        ray's predicted depth t* (:meth:`ray_depth`)."""

        def sample(o, d, rays, t_coarse, near, far, perturb, generator) -> torch.Tensor:
            with torch.no_grad():
                points = o[:, None, :] + t_coarse[..., None] * d[:, None, :]
                obj = ray_object[rays]
                t_star = torch.zeros_like(near)
                for b in torch.unique(obj).tolist():
                    sel = obj == b
                    t_star[sel] = self.ray_depth(encoding, b, points[sel], t_coarse[sel])
            return depth_band_samples(t_star, near, far, DEPTH_BAND, self.config.num_fine, perturb, generator)

        return sample

    def auxiliary_losses(
        self, encoding: GeoEncoding, input_depth: torch.Tensor | None = None, input_labels: torch.Tensor | None = None
    ) -> dict[str, torch.Tensor]:
        """``loss/source_depth``: :data:`SOURCE_DEPTH_WEIGHT` x :meth:`source_depth_loss` (empty without depth)."""
        if input_depth is None:
            return {}
        return {"loss/source_depth": SOURCE_DEPTH_WEIGHT * self.source_depth_loss(encoding, input_depth)}

    @staticmethod
    def source_depth_loss(encoding: GeoEncoding, depth: torch.Tensor) -> torch.Tensor:
        """Mean |predicted - true| z-depth (m) of the source views where the truth has a surface.

        Args:
            encoding: what :meth:`encode_views` returned.
            depth: (B, V, S, S) true z-depth of the input crops (m; 0 = no surface), aligned with the crops.
        """
        b, v, h, w = encoding.depth.shape
        target = F.interpolate(depth.reshape(b * v, 1, *depth.shape[-2:]), size=(h, w), mode="nearest")
        target = target.reshape(b, v, h, w)
        hit = target > 0
        if not bool(hit.any()):
            return encoding.depth.sum() * 0.0
        return (encoding.depth[hit] - target[hit]).abs().mean()
