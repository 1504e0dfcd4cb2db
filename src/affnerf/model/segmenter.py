"""The object segmenter: a network that finds the object of a photo among clutter, trained on our renders.

A generic salient-object model marks what stands out, which in a cluttered photo is often something else (a cup,
a face, a cat). This network is trained (:mod:`affnerf.train.segmenter`, ``affnerf train-segmenter``) on a dataset's
own object families pasted onto photographs and synthetic clutter, so it looks for *those* objects, as a detector
trained on its classes does. It is pure PyTorch and runs in a fraction of a second on a CPU. Two ship with affnerf,
voting as one :class:`SegmenterEnsemble` (``kind="u2netp"``, :func:`affnerf.predict.shipped.shipped_segmenter`;
``benchmarks/results/segmenter_u2netp.md``).

Network: an encoder of ``levels`` stages (two 3×3 conv + batch norm + ReLU, then 2× max pooling, channels doubling
from ``base``), a bottleneck that adds the image's mean feature to every cell (global context: which blob is the
object depends on the whole photo), and a decoder that upsamples and joins each encoder stage (U-Net skips). The
input is the photo resized so its larger side is ``input_side`` and padded to a multiple of ``2**levels``; the
output is one logit per pixel, brought back to the photo's size.

``kind="u2netp"`` swaps that network for U²-Net-p (:mod:`affnerf.model.u2netp`), the salient-object model's
network, which ``affnerf train-segmenter --init-salient`` starts from the salient model's own weights: features
learnt on thousands of real photographs, fine-tuned to find the dataset's families. Its input is the photo in 0..1,
normalised here as U²-Net expects, padded to a multiple of 32.
"""

from __future__ import annotations

import pickle
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np
import torch
from PIL import Image
from torch import nn
from torch.nn import functional as F

from affnerf.errors import input_error
from affnerf.model.segmenter_mask import (  # noqa: F401  (the mask's names, re-exported)
    SEGMENTER_EXTRA_CONFIDENCE,
    SEGMENTER_EXTRA_DISTANCE,
    SEGMENTER_EXTRA_SIZE,
    SEGMENTER_LOW_THRESHOLD,
    SEGMENTER_MAIN_MIN_SIZE,
    SEGMENTER_REGION_SURENESS_POWER,
    SEGMENTER_THRESHOLD,
    hysteresis_mask,
    mask_confidence,
    probability_mask,
)
from affnerf.model.u2netp import U2NetP, check_weights, load_onnx_weights, normalise, weights_path

#: Besides the whole photo, the segmenter sees four overlapping tiles of it (:func:`photo_probability`), each this
#: share of the photo's height and width, one at each corner, enlarged to the network's input: a small object (1-2 %
#: of the photo) is seen 1 / 0.6 times larger and without the photo's own subject beside it. Chosen on the composite
#: benchmark's seed-1 draws (shares 0.5 / 0.6 / 0.75: mean redrawn mask IoU 0.889 / 0.903 / 0.881, the whole photo
#: alone 0.880), checked on seeds 0 and 2-4 (240 composites: 0.891 against 0.869) and 5-8 (192: 0.905 against
#: 0.878); it costs four more passes of each network (``auto`` about 5.5 s an image on 2 cores, against 1.2 s), also
#: where the whole photo's mask is sure: the tiles still add its thin parts there (benchmarks/results/
#: segmenter_u2netp.md, "Tiles" and "Tiles on four new seeds").
SEGMENTER_TILE_SHARE = 0.6


@dataclass(frozen=True)
class SegmenterConfig:
    """Shape of the network.

    Attributes:
        kind: ``unet`` (this module's U-Net, from random weights) or ``u2netp`` (U²-Net-p, :mod:`affnerf.model.u2netp`;
            ``base`` and ``levels`` are then unused, its five poolings pad the input to a multiple of 32).
        base: channels of the first stage (doubled at each further stage).
        levels: encoder stages (the input is padded to a multiple of 2**levels).
        input_side: larger side, in pixels, of the photo as the network sees it.
    """

    kind: Literal["unet", "u2netp"] = "unet"
    base: int = 16
    levels: int = 4
    input_side: int = 192

    @property
    def multiple(self) -> int:
        """What the network's input sides must be multiples of."""
        return 32 if self.kind == "u2netp" else 2**self.levels


def conv_block(c_in: int, c_out: int) -> nn.Sequential:
    """Two 3×3 convolutions, each with batch norm and ReLU."""
    return nn.Sequential(
        nn.Conv2d(c_in, c_out, 3, padding=1, bias=False), nn.BatchNorm2d(c_out), nn.ReLU(inplace=True),
        nn.Conv2d(c_out, c_out, 3, padding=1, bias=False), nn.BatchNorm2d(c_out), nn.ReLU(inplace=True),
    )  # fmt: skip


class ObjectSegmenter(nn.Module):
    """U-Net with global context: (N, 3, H, W) images in 0..1 → (N, 1, H, W) object logits (H, W multiples of
    2**levels)."""

    def __init__(self, config: SegmenterConfig = SegmenterConfig()):
        super().__init__()
        self.config = config
        widths = [config.base * 2**i for i in range(config.levels + 1)]
        self.down = nn.ModuleList([conv_block(3, widths[0])])
        self.down.extend(conv_block(widths[i], widths[i + 1]) for i in range(config.levels))
        self.context = nn.Conv2d(2 * widths[-1], widths[-1], 1)
        ups = (conv_block(widths[i + 1] + widths[i], widths[i]) for i in reversed(range(config.levels)))
        self.up = nn.ModuleList(ups)
        self.head = nn.Conv2d(widths[0], 1, 1)

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        skips = []
        x = images - 0.5
        for i, block in enumerate(self.down):
            x = block(x if i == 0 else F.max_pool2d(x, 2))
            skips.append(x)
        pooled = x.mean(dim=(2, 3), keepdim=True).expand_as(x)
        x = F.relu(self.context(torch.cat([x, pooled], dim=1)))
        for block, skip in zip(self.up, reversed(skips[:-1]), strict=True):
            x = F.interpolate(x, size=skip.shape[-2:], mode="bilinear", align_corners=False)
            x = block(torch.cat([x, skip], dim=1))
        return self.head(x)


class SalientSegmenter(nn.Module):
    """U²-Net-p as an object segmenter: (N, 3, H, W) images in 0..1 → (N, 1, H, W) object logits."""

    def __init__(self, config: SegmenterConfig):
        super().__init__()
        self.config = config
        self.net = U2NetP()

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        return self.net(normalise(images))

    def side_logits(self, images: torch.Tensor) -> tuple[torch.Tensor, list[torch.Tensor]]:
        """Fused logits and the six side outputs' logits (U²-Net's deep supervision)."""
        return self.net.side_logits(normalise(images))


#: Either network: both take (N, 3, H, W) images in 0..1 and carry their ``config``.
Segmenter = ObjectSegmenter | SalientSegmenter


class SegmenterEnsemble(nn.Module):
    """Several trained segmenters that vote: the object probability of a photo is the mean of its members'
    (:func:`object_probability`), each member seeing the photo at its own ``input_side`` (a deep ensemble over
    networks and scales). Members trained apart go wrong on different photos, so where one loses the object the
    other often holds it (``benchmarks/results/segmenter_u2netp.md``, "Two segmenters voting"). For prediction
    only: training starts from a single network.
    """

    def __init__(self, members: list[Segmenter]):
        super().__init__()
        if not members:
            raise ValueError("a segmenter ensemble needs at least one member")
        self.members = nn.ModuleList(members)


#: What separates photos: one network or an ensemble of them.
AnySegmenter = Segmenter | SegmenterEnsemble


def build_segmenter(config: SegmenterConfig) -> Segmenter:
    """A new segmenter of ``config``'s kind, random weights."""
    return SalientSegmenter(config) if config.kind == "u2netp" else ObjectSegmenter(config)


def salient_segmenter(config: SegmenterConfig) -> SalientSegmenter:
    """A U²-Net-p segmenter of ``config``'s shape (its kind set to ``u2netp``) carrying the salient-object model's
    published weights (the optional extra ``affnerf[segment]``; SHA-256 checked), in eval mode.

    Raises:
        SalientUnavailable: the optional extra is not installed.
    """
    model = build_segmenter(replace(config, kind="u2netp"))
    path = weights_path()
    load_onnx_weights(model.net, check_weights(path), path)
    return model.eval()


def network_input(rgb: np.ndarray, config: SegmenterConfig) -> tuple[torch.Tensor, tuple[int, int]]:
    """(1, 3, H', W') float input of an (H, W, 3) uint8 photo, resized to a larger side of ``input_side`` and
    padded (edge values) at the bottom and right to multiples of ``config.multiple``, with the resized (W, H)
    before padding.

    Example:
        >>> x, size = network_input(np.zeros((300, 400, 3), np.uint8), SegmenterConfig())
        >>> tuple(x.shape), size
        ((1, 3, 144, 192), (192, 144))
    """
    h, w = rgb.shape[:2]
    s = config.input_side / max(h, w)
    size = (max(1, round(w * s)), max(1, round(h * s)))
    small = np.asarray(Image.fromarray(rgb).resize(size, Image.BILINEAR), np.float32) / 255.0
    m = config.multiple
    pad = (-size[1] % m, -size[0] % m)
    small = np.pad(small, ((0, pad[0]), (0, pad[1]), (0, 0)), mode="edge")
    return torch.from_numpy(np.ascontiguousarray(small.transpose(2, 0, 1)))[None], size


def vote(probabilities: list[np.ndarray]) -> np.ndarray:
    """(H, W) float32 object probability of an ensemble: the mean of its members' (H, W) probabilities.

    Example:
        >>> [round(float(p), 2) for p in vote([np.full((1, 2), 0.9), np.full((1, 2), 0.3)]).ravel()]
        [0.6, 0.6]
    """
    return np.mean(probabilities, axis=0).astype(np.float32)


@torch.no_grad()
def object_probability(model: AnySegmenter, rgb: np.ndarray) -> np.ndarray:
    """(H, W) float32 probability that each pixel of the (H, W, 3) uint8 photo is the object (an ensemble's: the
    mean of its members')."""
    if isinstance(model, SegmenterEnsemble):
        return vote([object_probability(m, rgb) for m in model.members])
    x, (w, h) = network_input(rgb, model.config)
    # channels-last input (oneDNN's preferred layout): the same probabilities to 4e-5, 1.4x faster on CPU
    # (benchmarks/results/segmenter_layout.json)
    logits = model(x.contiguous(memory_format=torch.channels_last))[0, 0, :h, :w]
    prob = torch.sigmoid(logits).numpy().astype(np.float32)
    full = Image.fromarray(prob, mode="F").resize((rgb.shape[1], rgb.shape[0]), Image.BILINEAR)
    return np.clip(np.asarray(full, np.float32), 0.0, 1.0)


def tile_windows(height: int, width: int, share: float = SEGMENTER_TILE_SHARE) -> list[tuple[int, int, int, int]]:
    """The four corner windows (y0, y1, x0, x1) of an image of ``height`` × ``width`` pixels, each ``share`` of its
    height and width (they overlap when ``share`` > 0.5).

    Example:
        >>> tile_windows(300, 400)
        [(0, 180, 0, 240), (0, 180, 160, 400), (120, 300, 0, 240), (120, 300, 160, 400)]
    """
    th, tw = max(1, round(height * share)), max(1, round(width * share))
    return [(y0, y0 + th, x0, x0 + tw) for y0 in (0, height - th) for x0 in (0, width - tw)]


def tiled_probability(model: AnySegmenter, rgb: np.ndarray, share: float = SEGMENTER_TILE_SHARE) -> np.ndarray:
    """(H, W) float32 object probability of the (H, W, 3) uint8 photo seen as its four corner tiles
    (:func:`tile_windows`), each through :func:`object_probability`: the mean of the tiles' maps where they
    overlap."""
    total = np.zeros(rgb.shape[:2], np.float32)
    count = np.zeros(rgb.shape[:2], np.float32)
    for y0, y1, x0, x1 in tile_windows(rgb.shape[0], rgb.shape[1], share):
        total[y0:y1, x0:x1] += object_probability(model, np.ascontiguousarray(rgb[y0:y1, x0:x1]))
        count[y0:y1, x0:x1] += 1.0
    return total / np.maximum(count, 1.0)


def photo_probability(model: AnySegmenter, rgb: np.ndarray, share: float | None = SEGMENTER_TILE_SHARE) -> np.ndarray:
    """(H, W) float32 object probability of a photo as ``predict`` reads it: per pixel the larger of the whole
    photo's map (:func:`object_probability`) and its tiles' (:func:`tiled_probability`; ``share`` None: the
    whole photo's alone). A small object that the whole photo's map misses beside a larger subject can win on a
    tile; the whole photo's map keeps what a tile cuts in two."""
    whole = object_probability(model, rgb)
    if share is None:
        return whole
    return np.maximum(whole, tiled_probability(model, rgb, share))


def _network_record(model: Segmenter) -> dict:
    """A network's config and a copy of its weights, as a segmenter file stores them."""
    return {"config": asdict(model.config), "state": {k: v.detach().clone() for k, v in model.state_dict().items()}}


def _network_from(record: dict) -> Segmenter:
    """The network of a :func:`_network_record`, in eval mode."""
    model = build_segmenter(SegmenterConfig(**record["config"]))
    model.load_state_dict(record["state"])
    return model.eval()


def save_segmenter(model: AnySegmenter, path: Path, provenance: dict | None = None) -> None:
    """Write the network's weights and config (an ensemble's: each member's, under ``members``) and
    ``provenance`` (how it was trained) to ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    if isinstance(model, SegmenterEnsemble):
        data = {"members": [_network_record(m) for m in model.members]}
    else:
        data = _network_record(model)
    torch.save({**data, "provenance": provenance or {}}, tmp)
    tmp.replace(path)


def read_segmenter(path: Path) -> AnySegmenter:
    """A new segmenter (or ensemble) with the weights in ``path``, in eval mode (not cached: safe to train
    further).

    Raises:
        AffnerfError: the file is missing or not a segmenter.
    """
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
        if "members" in data:
            return SegmenterEnsemble([_network_from(member) for member in data["members"]]).eval()
        return _network_from(data)
    except (OSError, RuntimeError, KeyError, TypeError, ValueError, EOFError, pickle.UnpicklingError) as err:
        raise input_error(path, f"not an affnerf object segmenter ({err})") from err


def networks(model: AnySegmenter) -> list[Segmenter]:
    """The single networks of ``model``: an ensemble's members, or the network itself."""
    return list(model.members) if isinstance(model, SegmenterEnsemble) else [model]


def combine_segmenters(paths: list[Path], out: Path, provenance: dict | None = None) -> SegmenterEnsemble:
    """Write to ``out`` the ensemble of the segmenters in ``paths`` (an ensemble among them joins with its
    members), each keeping its own network shape and input side; ``provenance`` is stored with it.

    Raises:
        AffnerfError: one of the files is missing or not a segmenter.
    """
    members: list[Segmenter] = []
    for path in paths:
        members += networks(read_segmenter(Path(path)))
    ensemble = SegmenterEnsemble(members).eval()
    save_segmenter(ensemble, Path(out), provenance)
    return ensemble


_LOADED: dict[Path, AnySegmenter] = {}


def load_segmenter(path: Path) -> AnySegmenter:
    """The segmenter in ``path``, in eval mode, loaded once per process and file.

    Raises:
        AffnerfError: the file is missing or not a segmenter.
    """
    path = Path(path)
    if path not in _LOADED:
        _LOADED[path] = read_segmenter(path)
    return _LOADED[path]
