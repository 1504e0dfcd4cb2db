"""The AFF-NeRF model: image -> (shape code, appearance code); rays + codes -> colour, depth, affordance."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.field import ObjectCodes
from affnerf.model.raymarch import Condition, FieldRenderer, RayOutputs
from affnerf.model.resnet import CodeEncoder

__all__ = ["AffNeRF", "Codes", "RayOutputs"]


@dataclass
class Codes:
    """Shape and appearance codes of B objects, each (B, code_dim)."""

    shape: torch.Tensor
    appearance: torch.Tensor


class AffNeRF(ConditionedNeRF):
    """Two ResNet18 encoders and a coarse and a fine field conditioned on their codes.

    The shape code joins PE(position) in the trunk (density, affordance, feature); the appearance code joins
    PE(direction) and the feature in the colour head.

    Args:
        config: architecture and sampling.
        num_classes: affordance classes including background.
    """

    needs_input_pose = False

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        self.shape_encoder = CodeEncoder(config.code_dim, config.encoder_width)
        self.appearance_encoder = CodeEncoder(config.code_dim, config.encoder_width)
        self.renderer = FieldRenderer(config, num_classes, config.code_dim, config.code_dim)

    def encode(self, images: torch.Tensor) -> Codes:
        """(B, 3, S, S) object crops in [0, 1] -> their codes."""
        return Codes(self.shape_encoder(images), self.appearance_encoder(images))

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> Codes:
        """Codes of B objects from V views each (B, V, 3, S, S): the mean of the views' codes.

        The cameras are not used: AFF-NeRF needs no input pose.
        """
        b, v = images.shape[:2]
        codes = self.encode(images.reshape(b * v, *images.shape[2:]))
        return Codes(codes.shape.reshape(b, v, -1).mean(1), codes.appearance.reshape(b, v, -1).mean(1))

    def condition(self, encoding: Codes, ray_object: torch.Tensor) -> Condition:
        """Each point takes its object's shape code (trunk) and appearance code (colour head).

        The codes are picked with a one-hot product rather than indexing: the gradient of an indexed read sums
        many points into few rows in an order that varies between runs on a multi-core CPU, and a resumed run must
        end with the same weights as an uninterrupted one. They stay factored (:class:`ObjectCodes`): the field
        multiplies each object's code with its weights once, not once per point.
        """

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[ObjectCodes, ObjectCodes]:
            pick = torch.nn.functional.one_hot(ray_object[rays], encoding.shape.shape[0]).to(encoding.shape.dtype)
            return ObjectCodes(encoding.shape, pick), ObjectCodes(encoding.appearance, pick)

        return cond
