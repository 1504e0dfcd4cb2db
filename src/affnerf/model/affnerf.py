"""The AFF-NeRF model: image -> (shape code, appearance code); rays + codes -> colour, depth, affordance."""

from __future__ import annotations

from dataclasses import dataclass, field

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
    """Shape and appearance codes of B objects, each (B, code_dim); while training a model with
    ``code_kl_weight``, ``kl`` (B,): each object's KL divergence of its codes' Gaussians from the prior
    (:func:`gaussian_kl`, both codes summed), else None."""

    shape: torch.Tensor
    appearance: torch.Tensor
    kl: torch.Tensor | None = field(default=None, kw_only=True)


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


def gaussian_kl(mean: torch.Tensor, log_var: torch.Tensor) -> torch.Tensor:
    """KL divergence of N(mean, exp(log_var)) from N(0, I), summed over the code's dimensions: (B, D) -> (B,).

    Example:
        >>> gaussian_kl(torch.zeros(1, 4), torch.zeros(1, 4)).tolist()
        [0.0]
    """
    return 0.5 * (mean.square() + log_var.exp() - 1.0 - log_var).sum(dim=-1)


#: Range the encoders' log-variances are clamped to before use, so a diverging head cannot blow a code up.
LOG_VARIANCE_RANGE = (-12.0, 4.0)


def sampled_codes(mean: torch.Tensor, log_var: torch.Tensor) -> torch.Tensor:
    """(B, D) codes drawn from N(mean, exp(log_var)) by the reparameterisation trick (gradients reach both).
    Draws from torch's global generator (saved in checkpoints)."""
    return mean + torch.randn_like(mean) * (0.5 * log_var).exp()


def variational_codes(
    codes: tuple[torch.Tensor, torch.Tensor], log_vars: tuple[torch.Tensor, torch.Tensor]
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Shape and appearance means and log-variances, (B, D) each -> the two sampled codes (:func:`sampled_codes`)
    and each object's KL summed over both codes, (B,); the log-variances clamped to :data:`LOG_VARIANCE_RANGE`."""
    shape_var, appearance_var = (v.clamp(*LOG_VARIANCE_RANGE) for v in log_vars)
    kl = gaussian_kl(codes[0], shape_var) + gaussian_kl(codes[1], appearance_var)
    return sampled_codes(codes[0], shape_var), sampled_codes(codes[1], appearance_var), kl


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
        variational = config.code_kl_weight > 0
        self.shape_encoder = CodeEncoder(
            config.code_dim,
            config.encoder_width,
            label_classes,
            second_code=one,
            pooling=config.shape_pooling,
            variational=variational,
        )
        self.appearance_encoder = (
            None if one else CodeEncoder(config.code_dim, config.encoder_width, variational=variational)
        )
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
        the codes with noise added (:func:`noisy_codes`); while training with ``code_kl_weight``, codes drawn from
        the encoders' Gaussians, with their KL (:func:`variational_codes`). Outside training, the means."""
        out = self.shape_encoder.encode_gaussian(images, labels=self.training)
        shape, shape_var, logits = out.code, out.code_log_var, out.logits
        appearance, appearance_var = out.second, out.second_log_var
        if self.appearance_encoder is not None:
            second = self.appearance_encoder.encode_gaussian(images, labels=False)
            appearance, appearance_var = second.code, second.code_log_var
        assert appearance is not None  # one encoder gives both codes
        kl = None
        if self.training and self.config.code_kl_weight > 0:
            assert shape_var is not None and appearance_var is not None  # the heads exist with the weight
            shape, appearance, kl = variational_codes((shape, appearance), (shape_var, appearance_var))
        if self.training and self.config.code_noise > 0:
            shape, appearance = (
                noisy_codes(shape, self.config.code_noise),
                noisy_codes(appearance, self.config.code_noise),
            )
        if logits is None:
            return Codes(shape, appearance, kl=kl)
        return LabelledCodes(shape, appearance, logits, kl=kl)

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> Codes:
        """Codes of B objects from V views each (B, V, 3, S, S): the mean of the views' codes (with the views'
        logits, (B, V, C, S / 4, S / 4), when :meth:`encode` gives them).

        The cameras are not used: AFF-NeRF needs no input pose.
        """
        b, v = images.shape[:2]
        codes = self.encode(images.reshape(b * v, *images.shape[2:]))
        shape, appearance = codes.shape.reshape(b, v, -1).mean(1), codes.appearance.reshape(b, v, -1).mean(1)
        kl = None if codes.kl is None else codes.kl.reshape(b, v).mean(1)
        if not isinstance(codes, LabelledCodes):
            return Codes(shape, appearance, kl=kl)
        logits = codes.view_logits.reshape(b, v, *codes.view_logits.shape[1:])
        return LabelledCodes(shape, appearance, logits, kl=kl)

    def auxiliary_losses(
        self, encoding: Codes, input_depth: torch.Tensor | None = None, input_labels: torch.Tensor | None = None
    ) -> dict[str, torch.Tensor]:
        """``loss/view_affordance``: ``view_affordance_weight`` x the cross-entropy of the shape encoder's pixel
        labels (:func:`view_label_loss`) against ``input_labels`` (absent without the head or the labels);
        ``loss/code_kl``: ``code_kl_weight`` x the objects' mean KL of their codes (absent without it)."""
        losses = {}
        if encoding.kl is not None:
            losses["loss/code_kl"] = self.config.code_kl_weight * encoding.kl.mean()
        if isinstance(encoding, LabelledCodes) and input_labels is not None and input_labels.numel():
            loss = view_label_loss(encoding.view_logits, input_labels)
            losses["loss/view_affordance"] = self.config.view_affordance_weight * loss
        return losses

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
