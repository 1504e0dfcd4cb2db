"""PixelNeRF-M, the paper's modified PixelNeRF baseline: pixel-aligned features with an affordance head.

Each input view goes through a ResNet18 whose first three stages are upsampled and stacked into a feature map
(as in PixelNeRF). A query point is projected into every input view with that view's camera; the feature found
there, with the point's position in the view's camera frame, passes a small network, and the views' results are
averaged. The average conditions the same coarse and fine fields as AFF-NeRF. Unlike AFF-NeRF it needs the input
cameras' poses.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional as F

from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.encoding import encoding_dim, positional_encoding
from affnerf.model.field import per_object
from affnerf.model.raymarch import Condition, FieldRenderer
from affnerf.model.resnet import ResNet18

#: Positional-encoding frequencies of a point's position in an input camera's frame.
VIEW_PE = 6


@dataclass
class PixelEncoding:
    """Feature maps and cameras of B objects' V input views.

    Attributes:
        features: (B, V, C, h, w) feature maps covering the crops.
        intrinsics: (B, V, 4) crop intrinsics (pixels of the S x S crop).
        world_to_camera: (B, V, 4, 4).
        size: the crop side S.
    """

    features: torch.Tensor
    intrinsics: torch.Tensor
    world_to_camera: torch.Tensor
    size: int


def project(points: torch.Tensor, w2c: torch.Tensor, intrinsics: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Points in a camera: (N, 3) world -> camera-frame positions (N, 3) and pixel coordinates (N, 2).

    Pixel (u, v) has its centre at (u + 0.5, v + 0.5), as in conventions §1; the camera looks along -z.
    """
    cam = points @ w2c[:3, :3].T + w2c[:3, 3]
    depth = (-cam[:, 2]).clamp(min=1e-4)
    u = intrinsics[0] * cam[:, 0] / depth + intrinsics[2]
    v = -intrinsics[1] * cam[:, 1] / depth + intrinsics[3]
    return cam, torch.stack([u, v], dim=-1)


def stack_stages(stages: list[torch.Tensor]) -> torch.Tensor:
    """ResNet stage outputs [(N, C_i, h_i, w_i)] -> (N, sum C_i, h_0, w_0): each upsampled to the first stage's size
    and stacked, PixelNeRF's multi-scale feature map."""
    size = stages[0].shape[-2:]
    up = [F.interpolate(s, size=size, mode="bilinear", align_corners=False) for s in stages[1:]]
    return torch.cat([stages[0], *up], 1)


def sample_features(features: torch.Tensor, pixels: torch.Tensor, size: int) -> torch.Tensor:
    """Bilinear read of a (C, h, w) feature map covering an S x S crop at (N, 2) crop pixel coordinates -> (N, C).

    Coordinates outside the crop read its border.
    """
    grid = (pixels / size * 2.0 - 1.0)[None, :, None, :]
    feat = F.grid_sample(features[None], grid, mode="bilinear", padding_mode="border", align_corners=False)
    return feat[0, :, :, 0].T


def pixel_aligned_code(
    net: nn.Module,
    features: torch.Tensor,
    world_to_camera: torch.Tensor,
    intrinsics: torch.Tensor,
    size: int,
    points: torch.Tensor,
) -> torch.Tensor:
    """Mean over V views of ``net``(feature read where each point projects, PE of its camera-frame position).

    Args:
        net: (C + PE dims) -> code MLP.
        features: (V, C, h, w) feature maps of one object's S x S crops.
        world_to_camera: (V, 4, 4); intrinsics: (V, 4) crop intrinsics; size: S.
        points: (N, 3) canonical positions.

    Returns:
        (N, code) codes.
    """
    codes = []
    for v in range(features.shape[0]):
        cam, pix = project(points, world_to_camera[v], intrinsics[v])
        feat = sample_features(features[v], pix, size)
        codes.append(net(torch.cat([feat, positional_encoding(cam, VIEW_PE)], dim=-1)))
    return torch.stack(codes).mean(0)


class PixelNeRF(ConditionedNeRF):
    """Pixel-aligned image features conditioning a radiance field with an affordance head.

    Args:
        config: architecture and sampling (``encoder_width``, ``encoder_resolution``, field sizes).
        num_classes: affordance classes including background.
    """

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        self.backbone = ResNet18(config.encoder_width, stages=3)
        self.feature_dim = sum(self.backbone.channels)
        cond = 2 * config.code_dim
        self.view_net = nn.Sequential(
            nn.Linear(self.feature_dim + encoding_dim(3, VIEW_PE), config.field_width),
            nn.ReLU(),
            nn.Linear(config.field_width, cond),
        )
        self.renderer = FieldRenderer(config, num_classes, cond, cond)

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> PixelEncoding:
        """Feature maps of (B, V, 3, S, S) crops, with their cameras."""
        b, v = images.shape[:2]
        stacked = stack_stages(self.backbone(images.reshape(b * v, *images.shape[2:])))
        return PixelEncoding(
            features=stacked.reshape(b, v, *stacked.shape[1:]),
            intrinsics=intrinsics,
            world_to_camera=torch.linalg.inv(poses),
            size=images.shape[-1],
        )

    def _object_condition(self, encoding: PixelEncoding, b: int, points: torch.Tensor) -> torch.Tensor:
        """(N, cond) mean over object b's input views of the projected features of (N, 3) points."""
        e = encoding
        return pixel_aligned_code(self.view_net, e.features[b], e.world_to_camera[b], e.intrinsics[b], e.size, points)

    def condition(self, encoding: PixelEncoding, ray_object: torch.Tensor) -> Condition:
        """Each point takes the averaged projected features of its object's input views (trunk and colour)."""

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            width = self.view_net[-1].out_features
            out = per_object(ray_object[rays], points, width, lambda b, p: self._object_condition(encoding, b, p))
            return out, out

        return cond
