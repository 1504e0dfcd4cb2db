"""The AFF-NeRF model: image -> (shape code, appearance code); rays + codes -> colour, depth, affordance."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.field import ObjectCodes, per_object
from affnerf.model.raymarch import Condition, FieldRenderer, RayOutputs
from affnerf.model.resnet import CodeEncoder
from affnerf.model.triplane import PlaneGenerator, sample_planes

__all__ = ["AffNeRF", "Codes", "LabelledCodes", "RayOutputs"]


@dataclass
class Codes:
    """Shape and appearance codes of B objects, each (B, code_dim)."""

    shape: torch.Tensor
    appearance: torch.Tensor


@dataclass
class LabelledCodes(Codes):
    """Codes with the shape encoder's pixel logits of the encoded crops, (B, V, C, S / 4, S / 4): what a model
    with ``view_affordance_weight`` > 0 encodes while training."""

    view_logits: torch.Tensor


def noisy_codes(codes: torch.Tensor, scale: float) -> torch.Tensor:
    """(B, D) codes plus Gaussian noise whose standard deviation in each dimension is ``scale`` times that
    dimension's standard deviation over the B codes (detached: the noise does not shrink the spread); the codes
    unchanged for B < 2 or ``scale`` 0. Draws from torch's global generator (saved in checkpoints)."""
    if scale <= 0 or codes.shape[0] < 2:
        return codes
    return codes + scale * codes.detach().std(dim=0, keepdim=True) * torch.randn_like(codes)


class AffNeRF(ConditionedNeRF):
    """Two ResNet18 encoders (or, with ``encoders`` ``one``, one with two linear heads) and a coarse and a fine
    field conditioned on their codes.

    The shape code joins PE(position) in the trunk (density, affordance, feature); the appearance code joins
    PE(direction) and the feature in the colour head. With ``triplane`` conditioning the trunk also reads each
    point's features from planes the shape code is decoded into (:mod:`affnerf.model.triplane`).

    Args:
        config: architecture and sampling.
        num_classes: affordance classes including background.
    """

    needs_input_pose = False

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        label_classes = num_classes if config.view_affordance_weight > 0 else 0
        one = config.encoders == "one"
        self.shape_encoder = CodeEncoder(
            config.code_dim, config.encoder_width, label_classes, second_code=one, pooling=config.shape_pooling
        )
        self.appearance_encoder = None if one else CodeEncoder(config.code_dim, config.encoder_width)
        self.planes: PlaneGenerator | None = None
        trunk_dim = config.code_dim
        if config.conditioning == "triplane":
            self.planes = PlaneGenerator(config.code_dim, config.plane_channels, config.plane_resolution)
            trunk_dim = 3 * config.plane_channels + config.code_dim
        self.renderer = FieldRenderer(config, num_classes, trunk_dim, config.code_dim)
        self._planes_memo: tuple[torch.Tensor, tuple[int, int, bool], torch.Tensor] | None = None

    def encode(self, images: torch.Tensor) -> Codes:
        """(B, 3, S, S) object crops in [0, 1] -> their codes; while training a model with a pixel-labelling head,
        :class:`LabelledCodes` with the crops' (B, C, S / 4, S / 4) logits; while training with ``code_noise``,
        the codes with noise added (:func:`noisy_codes`)."""
        shape, appearance, logits = self.shape_encoder.encode_both(images, labels=self.training)
        if self.appearance_encoder is not None:
            appearance = self.appearance_encoder(images)
        assert appearance is not None  # one encoder gives both codes
        if self.training and self.config.code_noise > 0:
            shape, appearance = (
                noisy_codes(shape, self.config.code_noise),
                noisy_codes(appearance, self.config.code_noise),
            )
        return Codes(shape, appearance) if logits is None else LabelledCodes(shape, appearance, logits)

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> Codes:
        """Codes of B objects from V views each (B, V, 3, S, S): the mean of the views' codes (with the views'
        logits, (B, V, C, S / 4, S / 4), when :meth:`encode` gives them).

        The cameras are not used: AFF-NeRF needs no input pose.
        """
        b, v = images.shape[:2]
        codes = self.encode(images.reshape(b * v, *images.shape[2:]))
        shape, appearance = codes.shape.reshape(b, v, -1).mean(1), codes.appearance.reshape(b, v, -1).mean(1)
        if not isinstance(codes, LabelledCodes):
            return Codes(shape, appearance)
        return LabelledCodes(shape, appearance, codes.view_logits.reshape(b, v, *codes.view_logits.shape[1:]))

    def auxiliary_losses(
        self, encoding: Codes, input_depth: torch.Tensor | None = None, input_labels: torch.Tensor | None = None
    ) -> dict[str, torch.Tensor]:
        """``loss/view_affordance``: ``view_affordance_weight`` x the cross-entropy of the shape encoder's pixel
        labels (:func:`view_label_loss`) against ``input_labels`` (empty without the head or the labels)."""
        if not isinstance(encoding, LabelledCodes) or input_labels is None or not input_labels.numel():
            return {}
        loss = view_label_loss(encoding.view_logits, input_labels)
        return {"loss/view_affordance": self.config.view_affordance_weight * loss}

    def condition(self, encoding: Codes, ray_object: torch.Tensor) -> Condition:
        """Each point takes its object's shape code (trunk) and appearance code (colour head).

        The codes are picked with a one-hot product rather than indexing: the gradient of an indexed read sums
        many points into few rows in an order that varies between runs on a multi-core CPU, and a resumed run must
        end with the same weights as an uninterrupted one. They stay factored (:class:`ObjectCodes`): the field
        multiplies each object's code with its weights once, not once per point. With ``triplane`` conditioning
        the trunk takes each point's reads of its object's planes beside its shape code, per point.
        """
        planes = None if self.planes is None else self.decode_planes(encoding.shape)

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[ObjectCodes | torch.Tensor, ObjectCodes]:
            pick = torch.nn.functional.one_hot(ray_object[rays], encoding.shape.shape[0]).to(encoding.shape.dtype)
            shape, appearance = ObjectCodes(encoding.shape, pick), ObjectCodes(encoding.appearance, pick)
            if planes is None:
                return shape, appearance
            half = self.config.scene_half_extent
            width = planes.shape[1] * planes.shape[2]
            feats = per_object(ray_object[rays], points, width, lambda b, p: sample_planes(planes[b], p, half))
            return torch.cat([feats, shape.per_point()], dim=-1), appearance

        return cond

    def decode_planes(self, shape: torch.Tensor) -> torch.Tensor:
        """(B, 3, C, R, R) triplanes of (B, code_dim) shape codes.

        The last result is kept while the code tensor, the generator's weights and the grad mode stay the same: a
        training step conditions its rays and its 3D points on one encoding, and whole images are rendered chunk by
        chunk, so the generator runs once for them all. The memo holds the code tensor itself, so its identity
        cannot pass to a new tensor.
        """
        assert self.planes is not None
        key = (shape._version, self.planes.stem.weight._version, torch.is_grad_enabled())
        memo = self._planes_memo
        if memo is None or memo[0] is not shape or memo[1] != key:
            memo = self._planes_memo = (shape, key, self.planes(shape))
        return memo[2]


def view_label_loss(logits: torch.Tensor, labels: torch.Tensor) -> torch.Tensor:
    """Mean cross-entropy of pixel logits (B, V, C, h, w), upsampled (bilinear) to the labels' (B, V, S, S) size,
    against those integer labels; 0-d."""
    b, v, c = logits.shape[:3]
    size = labels.shape[-2:]
    flat = torch.nn.functional.interpolate(logits.reshape(b * v, c, *logits.shape[-2:]), size=size, mode="bilinear")
    return torch.nn.functional.cross_entropy(flat, labels.reshape(b * v, *size).long())
