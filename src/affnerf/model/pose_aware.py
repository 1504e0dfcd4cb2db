"""AFF-NeRF, pose-aware (beyond the paper): global codes plus pixel-aligned features at a predicted input camera.

AFF-NeRF summarises the input image in two global codes, so detail the pooling loses (a handle's exact place, a
thin blade) cannot come back. PixelNeRF keeps that detail by projecting each query point into the input view, but
needs the view's pose, which a photo does not come with. This model predicts the pose: the shape encoder's pooled
features also give the input camera in the canonical frame (elevation, azimuth, distance, the crop's focal length
and where the origin sits in the crop; :mod:`affnerf.model.camera_head`), learned from the datasets' poses. Each
query point is projected with that predicted camera, the shape encoder's multi-scale feature map is read there
(PixelNeRF's way), and a small network turns the feature and the point's position in the predicted camera frame
into a local code that joins the global codes in the trunk and in the colour head.

The camera used for projection is the predicted one, detached: in training too, so that the fields learn to read
features through the same imperfect camera they get at prediction. The true camera only supervises the camera head
(:meth:`PoseAwareNeRF.auxiliary_losses`). Prediction therefore needs no pose, as AFF-NeRF's. With
``projection_camera="given"`` (an oracle for benchmarks) the true camera projects wherever it is given.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from affnerf.model.affnerf import Codes
from affnerf.model.base import ConditionedNeRF
from affnerf.model.camera_head import (
    CAMERA_PARAMS,
    PARAM_PRIOR,
    camera_errors,
    camera_from_params,
    camera_loss,
    params_from_camera,
)
from affnerf.model.config import ModelConfig
from affnerf.model.encoding import encoding_dim
from affnerf.model.field import per_object
from affnerf.model.pixelnerf import VIEW_PE, pixel_aligned_code, stack_stages
from affnerf.model.raymarch import Condition, FieldRenderer
from affnerf.model.resnet import CodeEncoder, ResNet18

__all__ = ["PoseAwareCodes", "PoseAwareNeRF"]


@dataclass
class PoseAwareCodes(Codes):
    """Global codes, feature maps and predicted cameras of B objects seen in V views.

    Attributes:
        shape: (B, code_dim) shape codes (mean over the views).
        appearance: (B, code_dim) appearance codes (mean over the views).
        features: (B, V, C, h, w) multi-scale feature maps of the crops.
        camera: (B, V, 7) predicted camera vectors (with their gradient, for the camera loss).
        world_to_camera: (B, V, 4, 4) the predicted cameras, detached.
        intrinsics: (B, V, 4) their crop intrinsics, detached.
        size: the crop side S.
        true_camera: (B, V, 7) the true camera vectors when the input poses were given, else None.
    """

    features: torch.Tensor
    camera: torch.Tensor
    world_to_camera: torch.Tensor
    intrinsics: torch.Tensor
    size: int
    true_camera: torch.Tensor | None = None


class PoseAwareNeRF(ConditionedNeRF):
    """Shape and appearance encoders, a camera head and pixel-aligned features at the predicted camera.

    Args:
        config: architecture and sampling (as AFF-NeRF's).
        num_classes: affordance classes including background.
    """

    needs_input_pose = False

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        self.shape_backbone = ResNet18(config.encoder_width)
        pooled = self.shape_backbone.channels[-1]
        self.shape_head = nn.Linear(pooled, config.code_dim)
        self.camera_head = nn.Sequential(nn.Linear(pooled, 64), nn.ReLU(), nn.Linear(64, CAMERA_PARAMS))
        nn.init.normal_(self.camera_head[-1].weight, std=1e-3)  # starts near the prior, gradient reaches below
        with torch.no_grad():
            self.camera_head[-1].bias.copy_(torch.tensor(PARAM_PRIOR))
        self.appearance_encoder = CodeEncoder(config.code_dim, config.encoder_width)
        feature_dim = sum(self.shape_backbone.channels[:3])
        self.local_net = nn.Sequential(
            nn.Linear(feature_dim + encoding_dim(3, VIEW_PE), config.field_width),
            nn.ReLU(),
            nn.Linear(config.field_width, config.code_dim),
        )
        cond = 2 * config.code_dim
        self.renderer = FieldRenderer(config, num_classes, cond, cond)

    def encode(self, images: torch.Tensor) -> PoseAwareCodes:
        """(B, 3, S, S) object crops in [0, 1], one per object, no pose -> their encoding."""
        return self._encode(images[:, None], None)

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> PoseAwareCodes:
        """Encoding of B objects from V views each (B, V, 3, S, S). The given cameras are the camera head's training
        target; they also project the query points only with ``projection_camera="given"``."""
        true = params_from_camera(poses.float(), intrinsics.float(), images.shape[-1])
        return self._encode(images, true)

    def _encode(self, images: torch.Tensor, true_camera: torch.Tensor | None) -> PoseAwareCodes:
        b, v, _, size, _ = images.shape
        flat = images.reshape(b * v, *images.shape[2:])
        stages = self.shape_backbone(flat)
        pooled = stages[-1].mean(dim=(2, 3))
        camera = self.camera_head(pooled)
        project = camera.detach()
        if true_camera is not None and self.config.projection_camera == "given":
            project = true_camera.reshape(camera.shape).to(camera.dtype)
        w2c, intrinsics = camera_from_params(project, size)
        return PoseAwareCodes(
            shape=self.shape_head(pooled).reshape(b, v, -1).mean(1),
            appearance=self.appearance_encoder(flat).reshape(b, v, -1).mean(1),
            features=stack_stages(stages[:3]).reshape(b, v, -1, *stages[0].shape[-2:]),
            camera=camera.reshape(b, v, -1),
            world_to_camera=w2c.reshape(b, v, 4, 4),
            intrinsics=intrinsics.reshape(b, v, 4),
            size=size,
            true_camera=true_camera,
        )

    def auxiliary_losses(
        self,
        encoding: PoseAwareCodes,
        input_depth: torch.Tensor | None = None,
        input_labels: torch.Tensor | None = None,
    ) -> dict[str, torch.Tensor]:
        """``loss/camera``: the camera head against the true input cameras (empty without them)."""
        if encoding.true_camera is None:
            return {}
        pred = encoding.camera.reshape(-1, encoding.camera.shape[-1])
        return {"loss/camera": camera_loss(pred, encoding.true_camera.reshape(pred.shape))}

    def camera_errors(self, encoding: PoseAwareCodes) -> dict[str, torch.Tensor]:
        """Errors of the predicted input cameras, each (B * V,) (see :func:`camera_head.camera_errors`)."""
        if encoding.true_camera is None:
            raise ValueError("the encoding was made without the input cameras")
        pred = encoding.camera.detach().reshape(-1, encoding.camera.shape[-1])
        return camera_errors(pred, encoding.true_camera.reshape(pred.shape))

    def _local_code(self, encoding: PoseAwareCodes, b: int, points: torch.Tensor) -> torch.Tensor:
        """(N, code_dim): mean over object b's views of the local code of (N, 3) points."""
        e = encoding
        return pixel_aligned_code(self.local_net, e.features[b], e.world_to_camera[b], e.intrinsics[b], e.size, points)

    def condition(self, encoding: PoseAwareCodes, ray_object: torch.Tensor) -> Condition:
        """Trunk: (shape code, local code); colour head: (appearance code, local code)."""

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            obj = ray_object[rays]
            local = per_object(obj, points, self.config.code_dim, lambda b, p: self._local_code(encoding, b, p))
            pick = torch.nn.functional.one_hot(obj, encoding.shape.shape[0]).to(local.dtype)
            return torch.cat([pick @ encoding.shape, local], -1), torch.cat([pick @ encoding.appearance, local], -1)

        return cond
