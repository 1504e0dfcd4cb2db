"""The composite benchmark's photos (issue 16): rendered objects pasted onto scikit-image's photographs of
cluttered scenes, with their true masks and seeded boxes, drawn the same way by every script that replays them
(``bench_segment.py``, the box rule, the true-mask and crop checks, the README's example).
"""

from __future__ import annotations

import argparse
import copy
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, ImageFilter

from affnerf.data.dataset import Dataset, ObjectData

#: scikit-image sample photographs of cluttered or textured scenes (all ship in the wheel, no download).
BACKGROUNDS = ("astronaut", "coffee", "chelsea", "rocket", "hubble_deep_field", "immunohistochemistry")
CANVAS = (400, 300)
#: ``--box`` rows: each side of the object's true bounding box moves out by this share of the box's size, drawn
#: uniformly per side (a detector's or a hand-drawn box, loose by a margin the user did not measure).
BOX_PADDING = (0.05, 0.25)
#: ``--box`` (tight) rows: a detector's box, at most 5 % larger than the object per side.
TIGHT_PADDING = (0.0, 0.05)


def backgrounds() -> dict[str, np.ndarray]:
    import skimage.data

    return {name: getattr(skimage.data, name)()[..., :3] for name in BACKGROUNDS}


def composite(obj_rgb: np.ndarray, obj_mask: np.ndarray, bg: np.ndarray, shadow: bool, rng) -> tuple:
    """(rgb, true mask) of the object pasted on a random canvas-sized cut of ``bg``."""
    w, h = CANVAS
    scale = max(w / bg.shape[1], h / bg.shape[0]) * rng.uniform(1.0, 1.5)
    big = np.asarray(Image.fromarray(bg).resize((round(bg.shape[1] * scale), round(bg.shape[0] * scale))))
    y, x = rng.integers(0, big.shape[0] - h + 1), rng.integers(0, big.shape[1] - w + 1)
    canvas = big[y : y + h, x : x + w].astype(np.float32)
    rows, cols = np.flatnonzero(obj_mask.any(1)), np.flatnonzero(obj_mask.any(0))
    cut = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    side = rng.uniform(0.35, 0.7) * h / max(rows[-1] - rows[0] + 1, cols[-1] - cols[0] + 1)
    size = (max(4, round((cols[-1] - cols[0] + 1) * side)), max(4, round((rows[-1] - rows[0] + 1) * side)))
    rgb = np.asarray(Image.fromarray(obj_rgb[cut]).resize(size, Image.BILINEAR), np.float32)
    alpha = np.asarray(Image.fromarray(obj_mask[cut].astype(np.uint8) * 255).resize(size, Image.BILINEAR))
    ox, oy = rng.integers(8, w - size[0] - 8), rng.integers(8, h - size[1] - 8)
    full = np.zeros((h, w), np.uint8)
    full[oy : oy + size[1], ox : ox + size[0]] = alpha
    if shadow:
        dx, dy = rng.integers(4, 14, 2)
        shade = np.roll(np.roll(full, dy, 0), dx, 1)
        shade = np.asarray(Image.fromarray(shade).filter(ImageFilter.GaussianBlur(6)), np.float32) / 255.0
        canvas *= 1.0 - 0.55 * shade[..., None]
    a = (full.astype(np.float32) / 255.0)[..., None]
    patch = np.zeros_like(canvas)
    patch[oy : oy + size[1], ox : ox + size[0]] = rgb
    out = np.clip(np.round(a * patch + (1 - a) * canvas), 0, 255).astype(np.uint8)
    return out, full > 127


def padded_box(
    truth: np.ndarray, rng: np.random.Generator, padding: tuple[float, float] = BOX_PADDING
) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) of the true mask's bounding box, each side moved out by a random share (``padding``) of
    the box's size, clipped to the image."""
    rows, cols = np.flatnonzero(truth.any(1)), np.flatnonzero(truth.any(0))
    bh, bw = rows[-1] - rows[0] + 1, cols[-1] - cols[0] + 1
    left, top, right, bottom = rng.uniform(*padding, 4)
    h, w = truth.shape
    return (
        max(0, int(cols[0] - left * bw)),
        max(0, int(rows[0] - top * bh)),
        min(w, int(cols[-1] + 1 + right * bw)),
        min(h, int(rows[-1] + 1 + bottom * bh)),
    )


@dataclass
class BenchComposite:
    """One composite of the benchmark, as :func:`bench_composites` draws it.

    Attributes:
        index: its place in the draw order (``k``).
        obj, view: the object and the dataset view pasted.
        background, shadow: the photograph's name (:data:`BACKGROUNDS`) and whether a drop shadow was cast.
        rgb: (H, W, 3) uint8 composite; truth: (H, W) bool true mask.
        box, tight_box: the true bounding box loosened by :data:`BOX_PADDING` and :data:`TIGHT_PADDING` per side.
        draws: the random generator as it was before this composite was pasted: :func:`composite` with a copy of it
            pastes the object at the same size and place onto another background.
    """

    index: int
    obj: ObjectData
    view: int
    background: str
    shadow: bool
    rgb: np.ndarray
    truth: np.ndarray
    box: tuple[int, int, int, int]
    tight_box: tuple[int, int, int, int]
    draws: np.random.Generator


def bench_composites(data: Path, seed: int, count: int) -> Iterator[BenchComposite]:
    """The benchmark's first ``count`` composites for ``seed``, in order: every script that replays them (the
    examples, the box rule, the true-mask check) gets the same objects, views, placements and boxes."""
    rng = np.random.default_rng(seed)
    ds = Dataset.open(data)
    entries = ds.objects()
    picks = rng.permutation(len(entries))[:count]
    bgs = backgrounds()
    box_rng = np.random.default_rng(seed + 1)  # its own stream: the composites stay those of earlier runs
    tight_rng = np.random.default_rng(seed + 2)
    for k, idx in enumerate(picks):
        obj = ds.load_object(entries[idx])
        view = int(rng.integers(len(obj.record.frames)))
        shadow, bg = bool(k % 2), BACKGROUNDS[k % len(BACKGROUNDS)]
        draws = copy.deepcopy(rng)
        rgb, truth = composite(obj.rgb(view), obj.affordance(view) > 0, bgs[bg], shadow, rng)
        box, tight = padded_box(truth, box_rng), padded_box(truth, tight_rng, TIGHT_PADDING)
        yield BenchComposite(k, obj, view, bg, shadow, rgb, truth, box, tight, draws)


def replay_args(doc: str) -> argparse.Namespace:
    """``--data``, ``--composites`` (24) and ``--out`` of a script that replays the first composites' predictions
    (``segment_true_mask.py``, ``segment_crop_box.py``)."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--composites", type=int, default=24)
    parser.add_argument("--out", type=Path, required=True)
    return parser.parse_args()


def seed_sweep_parser(doc: str) -> argparse.ArgumentParser:
    """A parser with ``--data``, ``--seeds`` (1), ``--composites`` (48), ``--threads`` (1) and ``--out`` for a script
    that scores segmenter choices over the first composites of several seeds (``segmenter_thin.py``,
    ``segment_thin_fragments.py``); the script adds its own options."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1])
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--out", type=Path, required=True)
    return parser
