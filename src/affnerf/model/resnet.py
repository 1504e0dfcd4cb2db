"""ResNet18 in plain torch, with a width multiplier and GroupNorm, trained from scratch.

Normalisation: training feeds the encoders a handful of images per step (one per object, a few objects), and
prediction feeds one. BatchNorm's statistics over four images are noisy and differ between training and
inference; GroupNorm normalises each image on its own, so an image encodes the same way in a batch of one or
of many, in training and at prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn


def group_norm(channels: int, max_groups: int = 8) -> nn.GroupNorm:
    """GroupNorm with the largest group count <= ``max_groups`` that divides ``channels``."""
    groups = max(g for g in range(1, max_groups + 1) if channels % g == 0)
    return nn.GroupNorm(groups, channels)


class BasicBlock(nn.Module):
    """Two 3x3 convolutions with a residual connection (projected when the shape changes)."""

    def __init__(self, c_in: int, c_out: int, stride: int) -> None:
        super().__init__()
        self.conv1 = nn.Conv2d(c_in, c_out, 3, stride, 1, bias=False)
        self.norm1 = group_norm(c_out)
        self.conv2 = nn.Conv2d(c_out, c_out, 3, 1, 1, bias=False)
        self.norm2 = group_norm(c_out)
        self.shortcut: nn.Module = nn.Identity()
        if stride != 1 or c_in != c_out:
            self.shortcut = nn.Sequential(nn.Conv2d(c_in, c_out, 1, stride, bias=False), group_norm(c_out))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = torch.relu(self.norm1(self.conv1(x)))
        y = self.norm2(self.conv2(y))
        return torch.relu(y + self.shortcut(x))


class ResNet18(nn.Module):
    """ResNet18 feature extractor: (B, 3, H, W) images in [0, 1] -> feature maps of four stages.

    Args:
        width: channel multiplier; 1.0 gives the standard 64-128-256-512 channels.
        stages: how many of the four stages to build (feature extractors that stop early need fewer).
    """

    def __init__(self, width: float = 1.0, stages: int = 4) -> None:
        super().__init__()
        chans = [max(8, int(round(c * width))) for c in (64, 128, 256, 512)][:stages]
        self.channels = chans
        self.stem = nn.Sequential(
            nn.Conv2d(3, chans[0], 7, 2, 3, bias=False), group_norm(chans[0]), nn.ReLU(), nn.MaxPool2d(3, 2, 1)
        )
        layers = []
        c_in = chans[0]
        for i, c in enumerate(chans):
            stride = 1 if i == 0 else 2
            layers.append(nn.Sequential(BasicBlock(c_in, c, stride), BasicBlock(c, c, 1)))
            c_in = c
        self.layers = nn.ModuleList(layers)
        for m in self.modules():
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight, mode="fan_out", nonlinearity="relu")

    def forward(self, images: torch.Tensor) -> list[torch.Tensor]:
        """Feature maps after each stage: [(B, C_i, H / 2^(i+2), W / 2^(i+2))]."""
        x = self.stem(images * 2.0 - 1.0)
        feats = []
        for layer in self.layers:
            x = layer(x)
            feats.append(x)
        return feats


def stacked_features(feats: list[torch.Tensor]) -> torch.Tensor:
    """Every stage's feature map resized (bilinear) to the first stage's size and stacked along channels:
    [(B, C_i, H_i, W_i)] -> (B, sum C_i, H_0, W_0)."""
    size = feats[0].shape[-2:]
    resized = [f if f.shape[-2:] == size else nn.functional.interpolate(f, size=size, mode="bilinear") for f in feats]
    return torch.cat(resized, dim=1)


@dataclass
class EncoderOutput:
    """What :meth:`CodeEncoder.encode_gaussian` gives for B images: the code (B, D); the second code (B, D) or
    None; pixel logits (B, C, H / 4, W / 4) or None; the codes' log-variances (B, D) or None without
    ``variational`` heads (the second's also None without a second code)."""

    code: torch.Tensor
    second: torch.Tensor | None
    logits: torch.Tensor | None
    code_log_var: torch.Tensor | None
    second_log_var: torch.Tensor | None


#: Bias the log-variance heads of a ``variational`` :class:`CodeEncoder` start from: a standard deviation of about
#: 0.05, so training starts close to plain codes and the KL term widens them only as far as the rendering losses
#: allow (a variance of 1 from the first step drowns the untrained codes in noise and the decoder learns to
#: ignore them, a VAE's posterior collapse).
INITIAL_LOG_VARIANCE = -6.0


#: Stages (0-based) whose feature maps give keypoints in :class:`CodeEncoder`'s ``keypoints`` pooling: the second
#: and third (H / 8 and H / 16: 8 x 8 and 4 x 4 cells of a 64-pixel crop).
KEYPOINT_STAGES = (1, 2)


def spatial_soft_argmax(features: torch.Tensor) -> torch.Tensor:
    """Each channel's expected image position under a softmax over its map (Levine et al. 2016's spatial
    soft-argmax): (B, C, H, W) -> (B, 2C) coordinates in [-1, 1], x then y of each channel (cell centres).

    Example:
        >>> f = torch.zeros(1, 1, 4, 4); f[0, 0, 3, 0] = 50.0   # a peak in the bottom-left cell
        >>> spatial_soft_argmax(f).round(decimals=2).tolist()
        [[-0.75, 0.75]]
    """
    b, c, h, w = features.shape
    weights = torch.softmax(features.reshape(b, c, h * w), dim=-1).reshape(b, c, h, w)
    xs = torch.linspace(-1 + 1 / w, 1 - 1 / w, w, dtype=features.dtype, device=features.device)
    ys = torch.linspace(-1 + 1 / h, 1 - 1 / h, h, dtype=features.dtype, device=features.device)
    x = (weights.sum(dim=2) * xs).sum(dim=-1)
    y = (weights.sum(dim=3) * ys).sum(dim=-1)
    return torch.stack([x, y], dim=-1).reshape(b, 2 * c)


class CodeEncoder(nn.Module):
    """An image to a global code: ResNet18, global average pooling, a linear layer; optionally also per-pixel
    class logits of the image (a 1x1 convolution over all four stages' features, :func:`stacked_features`).

    Args:
        code_dim: size of the code (32 in the paper).
        width: ResNet18 channel multiplier.
        label_classes: classes of the pixel labelling head (0: no head, the paper's encoder).
        second_code: also give a second code of the same size from the same pooled features (its own linear
            layer, ``second_head``): one trunk for two codes.
        pooling: ``mean`` (the paper: the last stage averaged over the image) or ``keypoints`` (beyond the paper:
            also the :func:`spatial_soft_argmax` of every channel of the :data:`KEYPOINT_STAGES`, where in the
            crop each feature peaks, which the average forgets).
        variational: also give each code's log-variance per dimension from the same pooled features (a linear
            layer per code, ``log_var_head`` / ``second_log_var_head``): the code becomes the mean of a Gaussian
            (:meth:`encode_gaussian`), as a VAE's encoder gives.
    """

    def __init__(
        self,
        code_dim: int = 32,
        width: float = 1.0,
        label_classes: int = 0,
        second_code: bool = False,
        pooling: str = "mean",
        variational: bool = False,
    ) -> None:
        super().__init__()
        if pooling not in ("mean", "keypoints"):
            raise ValueError(f"pooling is mean or keypoints, not {pooling!r}")
        self.backbone = ResNet18(width)
        self.pooling = pooling
        pooled = self.backbone.channels[-1]
        if pooling == "keypoints":
            pooled += 2 * sum(self.backbone.channels[i] for i in KEYPOINT_STAGES)
        self.head = nn.Linear(pooled, code_dim)
        self.second_head = nn.Linear(pooled, code_dim) if second_code else None
        self.log_var_head = nn.Linear(pooled, code_dim) if variational else None
        self.second_log_var_head = nn.Linear(pooled, code_dim) if variational and second_code else None
        for layer in (self.log_var_head, self.second_log_var_head):
            if layer is not None:
                nn.init.constant_(layer.bias, INITIAL_LOG_VARIANCE)
        self.label_head = nn.Conv2d(sum(self.backbone.channels), label_classes, 1) if label_classes else None

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """(B, 3, H, W) images in [0, 1] -> (B, code_dim) codes."""
        return self.encode(images, labels=False)[0]

    def encode(self, images: torch.Tensor, labels: bool = True) -> tuple[torch.Tensor, torch.Tensor | None]:
        """(B, 3, H, W) images in [0, 1] -> (B, code_dim) codes and, with ``labels`` and a labelling head,
        (B, label_classes, H / 4, W / 4) pixel logits (else None)."""
        code, _, logits = self.encode_both(images, labels)
        return code, logits

    def pool(self, feats: list[torch.Tensor]) -> torch.Tensor:
        """The backbone's stage feature maps -> (B, F) pooled features (``pooling``)."""
        pooled = feats[-1].mean(dim=(2, 3))
        if self.pooling == "mean":
            return pooled
        return torch.cat([pooled, *(spatial_soft_argmax(feats[i]) for i in KEYPOINT_STAGES)], dim=1)

    def encode_both(
        self, images: torch.Tensor, labels: bool = True
    ) -> tuple[torch.Tensor, torch.Tensor | None, torch.Tensor | None]:
        """As :meth:`encode`, with the second code (B, code_dim) between them (None without ``second_code``)."""
        out = self.encode_gaussian(images, labels)
        return out.code, out.second, out.logits

    def encode_gaussian(self, images: torch.Tensor, labels: bool = True) -> EncoderOutput:
        """(B, 3, H, W) images in [0, 1] -> :class:`EncoderOutput`: the code(s), (B, code_dim) each, their
        log-variances with ``variational`` heads (else None) and, as :meth:`encode`, the pixel logits."""
        feats = self.backbone(images)
        pooled = self.pool(feats)

        def head(layer: nn.Linear | None) -> torch.Tensor | None:
            return None if layer is None else layer(pooled)

        logits = self.label_head(stacked_features(feats)) if labels and self.label_head is not None else None
        return EncoderOutput(
            self.head(pooled),
            head(self.second_head),
            logits,
            head(self.log_var_head),
            head(self.second_log_var_head),
        )
