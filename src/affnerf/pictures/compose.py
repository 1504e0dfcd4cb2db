"""Composing pictures from arrays: depth colouring, affordance overlays, text, legends, grids (uint8 RGB)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from affnerf.vocab import AFFORDANCE_PALETTE, colorize_labels

#: Anchor colours of the depth colour map, near (warm) to far (cool).
_DEPTH_ANCHORS = np.array([[253, 231, 37], [94, 201, 98], [33, 145, 140], [59, 82, 139], [68, 1, 84]], dtype=np.float64)


def depth_to_color(depth: np.ndarray, near: float | None = None, far: float | None = None) -> np.ndarray:
    """Colour a (H, W) depth map in metres; pixels without surface (0) are black.

    Args:
        depth: z-depth, 0 = none.
        near: depth shown in the nearest colour (default: the map's smallest positive depth).
        far: depth shown in the farthest colour (default: its largest).

    Returns:
        (H, W, 3) uint8.
    """
    valid = depth > 0
    out = np.zeros(depth.shape + (3,), np.uint8)
    if not valid.any():
        return out
    lo = float(depth[valid].min()) if near is None else near
    hi = float(depth[valid].max()) if far is None else far
    t = np.clip((depth[valid] - lo) / max(hi - lo, 1e-9), 0.0, 1.0) * (len(_DEPTH_ANCHORS) - 1)
    i = np.minimum(np.floor(t).astype(np.int64), len(_DEPTH_ANCHORS) - 2)
    f = (t - i)[:, None]
    out[valid] = np.round(_DEPTH_ANCHORS[i] * (1 - f) + _DEPTH_ANCHORS[i + 1] * f).astype(np.uint8)
    return out


def overlay_affordance(rgb: np.ndarray, labels: np.ndarray, alpha: float = 0.6) -> np.ndarray:
    """Blend affordance colours over an image where ``labels`` > 0.

    Args:
        rgb: (H, W, 3) uint8.
        labels: (H, W) class ids.
        alpha: weight of the class colour.

    Returns:
        (H, W, 3) uint8.
    """
    out = rgb.astype(np.float64)
    mask = labels > 0
    out[mask] = (1 - alpha) * out[mask] + alpha * colorize_labels(labels[mask])
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


def _font(size: int = 12) -> ImageFont.ImageFont:
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow without FreeType
        return ImageFont.load_default()


def text_strip(text: str, width: int, height: int = 18, background: int = 255) -> np.ndarray:
    """A (height, width, 3) uint8 strip with ``text`` written in black at its left."""
    image = Image.new("RGB", (width, height), (background,) * 3)
    ImageDraw.Draw(image).text((4, 2), text, fill=(0, 0, 0), font=_font(height - 6))
    return np.asarray(image)


def legend(class_ids: Sequence[int], names: Sequence[str], width: int, height: int = 22) -> np.ndarray:
    """A (height, width, 3) uint8 strip of colour swatches and names for the given class ids."""
    image = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(image)
    font = _font(height - 8)
    x = 4
    for cid in class_ids:
        color = tuple(int(c) for c in AFFORDANCE_PALETTE[cid % len(AFFORDANCE_PALETTE)])
        draw.rectangle([x, 4, x + height - 8, height - 4], fill=color, outline=(0, 0, 0))
        x += height - 4
        label = names[cid] if cid < len(names) else str(cid)
        draw.text((x, 3), label, fill=(0, 0, 0), font=font)
        x += int(draw.textlength(label, font=font)) + 12
    return np.asarray(image)


def grid(rows: Sequence[Sequence[np.ndarray]], pad: int = 2, fill: int = 255) -> np.ndarray:
    """Tile images (each (H, W, 3) uint8, any sizes) into rows; short rows and small tiles are padded."""
    tile_h = max(im.shape[0] for row in rows for im in row)
    tile_w = max(im.shape[1] for row in rows for im in row)
    ncols = max(len(row) for row in rows)
    out = np.full((len(rows) * (tile_h + pad) + pad, ncols * (tile_w + pad) + pad, 3), fill, dtype=np.uint8)
    for r, row in enumerate(rows):
        for c, im in enumerate(row):
            y, x = pad + r * (tile_h + pad), pad + c * (tile_w + pad)
            out[y : y + im.shape[0], x : x + im.shape[1]] = im
    return out


def stack_rows(parts: Sequence[np.ndarray], fill: int = 255) -> np.ndarray:
    """Stack images vertically, padding narrower ones on the right."""
    width = max(p.shape[1] for p in parts)
    padded = [
        np.concatenate([p, np.full((p.shape[0], width - p.shape[1], 3), fill, np.uint8)], 1)
        if p.shape[1] < width
        else p
        for p in parts
    ]
    return np.concatenate(padded, 0)


def fit_height(image: np.ndarray, height: int) -> np.ndarray:
    """Resize (keeping the aspect ratio) to ``height`` rows."""
    width = max(1, round(image.shape[1] * height / image.shape[0]))
    return np.asarray(Image.fromarray(image).convert("RGB").resize((width, height), Image.LANCZOS))
