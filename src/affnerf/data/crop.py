"""Object-centred square crops: what the encoders see, in training and at prediction alike.

A crop is the square around the object's bounding box, enlarged by a margin, filled with the background colour
where it leaves the image (or, for a model whose ``crop_outside`` is ``checker``, marked there by a checkerboard),
and resized. Encoding crops rather than whole frames removes the camera's distance
and framing from what the codes must explain, and lets any photo be prepared the same way.
"""

from __future__ import annotations

import numpy as np
from PIL import Image

#: Fraction of the box side added on each side of the object.
CROP_MARGIN = 0.08
#: Side in crop pixels of the squares of the checkerboard that marks where a crop leaves the image
#: (:func:`mark_outside`).
CHECKER_SQUARE = 4


def object_bbox(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1), end exclusive, of the True pixels of an (H, W) mask; None if there are none.

    Example:
        >>> m = np.zeros((4, 5), bool); m[1:3, 2:4] = True
        >>> object_bbox(m)
        (2, 1, 4, 3)
    """
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if not len(rows):
        return None
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


def touches_border(mask: np.ndarray) -> np.ndarray:
    """Whether the object reaches the image's border, so the frame may cut part of it off.

    Args:
        mask: (..., H, W) bool, True on the object.

    Returns:
        (...) bool.

    Example:
        >>> m = np.zeros((2, 3, 4), bool); m[0, 1, 1] = True; m[1, 1, 3] = True
        >>> touches_border(m).tolist()
        [False, True]
    """
    rows = mask[..., 0, :].any(-1) | mask[..., -1, :].any(-1)
    return rows | mask[..., :, 0].any(-1) | mask[..., :, -1].any(-1)


def square_box(bbox: tuple[int, int, int, int], margin: float = CROP_MARGIN) -> tuple[float, float, float]:
    """Centre (cx, cy) and side of the square around ``bbox`` grown by ``margin`` of its larger side each way."""
    x0, y0, x1, y1 = bbox
    side = max(x1 - x0, y1 - y0) * (1.0 + 2.0 * margin)
    return (x0 + x1) / 2.0, (y0 + y1) / 2.0, max(side, 1.0)


def crop_window(mask: np.ndarray, margin: float = CROP_MARGIN) -> tuple[int, int, int]:
    """(left, top, side) in whole pixels of the square cut out around the object (the image's centre square
    when the mask is empty); it may reach outside the image."""
    h, w = mask.shape
    bbox = object_bbox(mask)
    cx, cy, side = square_box(bbox, margin) if bbox else (w / 2.0, h / 2.0, float(min(h, w)))
    return int(np.floor(cx - side / 2.0)), int(np.floor(cy - side / 2.0)), int(np.ceil(side))


def crop_intrinsics(
    fl_x: float, fl_y: float, cx: float, cy: float, window: tuple[int, int, int], size: int
) -> tuple[float, float, float, float]:
    """The pinhole intrinsics of a crop: the image's, shifted to the window and scaled to ``size`` pixels.

    Example:
        >>> crop_intrinsics(100.0, 100.0, 50.0, 40.0, (10, 0, 80), 40)
        (50.0, 50.0, 20.0, 20.0)
    """
    scale = size / window[2]
    return fl_x * scale, fl_y * scale, (cx - window[0]) * scale, (cy - window[1]) * scale


def resample_to_crop(
    image: np.ndarray, intrinsics: np.ndarray, crop_k: np.ndarray | tuple[float, ...], size: int
) -> np.ndarray:
    """An image of the same camera (a depth map, say) seen through a crop's pixels: the nearest image pixel to
    each crop pixel's centre, 0 where that falls outside the image.

    Args:
        image: (H, W) or (H, W, C) array.
        intrinsics: (4,) fl_x, fl_y, cx, cy of ``image``.
        crop_k: (4,) fl_x, fl_y, cx, cy of the crop (:func:`crop_intrinsics`, at any image resolution).
        size: the crop's side in pixels.

    Returns:
        (size, size) or (size, size, C), the dtype of ``image``.

    Example:
        >>> depth = np.arange(16.0).reshape(4, 4)
        >>> resample_to_crop(depth, np.array([4.0, 4.0, 2.0, 2.0]), (2.0, 2.0, 1.0, 1.0), 2).tolist()
        [[5.0, 7.0], [13.0, 15.0]]
    """
    centres = np.arange(size) + 0.5
    u = np.floor((centres - crop_k[2]) / crop_k[0] * intrinsics[0] + intrinsics[2]).astype(np.int64)
    v = np.floor((centres - crop_k[3]) / crop_k[1] * intrinsics[1] + intrinsics[3]).astype(np.int64)
    h, w = image.shape[:2]
    inside = (v[:, None] >= 0) & (v[:, None] < h) & (u[None, :] >= 0) & (u[None, :] < w)
    out = image[np.clip(v, 0, h - 1)[:, None], np.clip(u, 0, w - 1)[None, :]]
    return np.where(inside.reshape(inside.shape + (1,) * (out.ndim - 2)), out, 0).astype(image.dtype)


def crop_object(
    rgb: np.ndarray,
    mask: np.ndarray,
    size: int,
    background: tuple[float, float, float] | np.ndarray,
    margin: float = CROP_MARGIN,
    outside: str = "background",
) -> np.ndarray:
    """The object-centred square crop of an image.

    Args:
        rgb: (H, W, 3) uint8 image.
        mask: (H, W) bool, True on the object.
        size: side of the output in pixels.
        background: RGB in [0, 1] filling what lies outside the image (and replacing non-object pixels, so the
            crop shows the object on a clean background whatever the photo's surroundings).
        margin: see :func:`square_box`.
        outside: what the crop shows where it leaves the image (``ModelConfig.crop_outside``): ``background`` or a
            ``checker`` board (:func:`mark_outside`).

    Returns:
        (size, size, 3) uint8, the window of :func:`crop_window` resized.
    """
    bg = np.round(np.asarray(background, np.float64) * 255).astype(np.uint8)
    clean = np.where(mask[..., None], rgb, bg)
    left, top, side = crop_window(mask, margin)
    canvas = Image.new("RGB", (side, side), tuple(int(c) for c in bg))
    canvas.paste(Image.fromarray(np.ascontiguousarray(clean)), (-left, -top))
    crop = np.array(canvas.resize((size, size), Image.BILINEAR))
    if outside == "checker":
        return mark_outside(crop, outside_image((left, top, side), mask.shape, size))
    return crop


def crop_outside(
    image_shape: tuple[int, int], intrinsics: np.ndarray, crop_k: np.ndarray | tuple[float, ...], size: int
) -> np.ndarray:
    """(size, size) bool: the pixels of a crop (intrinsics ``crop_k``) of an image of ``image_shape`` (H, W) and
    ``intrinsics`` whose centre falls outside that image, by :func:`resample_to_crop`'s nearest-pixel rule."""
    return ~resample_to_crop(np.ones(image_shape, bool), np.asarray(intrinsics, np.float64), crop_k, size)


def outside_image(window: tuple[int, int, int], image_shape: tuple[int, int], size: int) -> np.ndarray:
    """:func:`crop_outside` of the crop of ``window`` (left, top, side, from :func:`crop_window`).

    Example:
        >>> outside_image((-2, 0, 4), (4, 4), 4)[0].tolist()
        [True, True, False, False]
    """
    unit = np.array([1.0, 1.0, 0.0, 0.0])
    return crop_outside(image_shape, unit, crop_intrinsics(1.0, 1.0, 0.0, 0.0, window, size), size)


def mark_outside(crop: np.ndarray, outside: np.ndarray, square: int = CHECKER_SQUARE) -> np.ndarray:
    """A crop whose pixels outside the image show a black and white checkerboard instead of the background, so an
    encoder can tell "the image ends here" from "nothing is there" (an object cut off by the frame).

    Args:
        crop: (S, S, 3) uint8.
        outside: (S, S) bool, from :func:`outside_image`.
        square: side of the checkerboard's squares in pixels.

    Returns:
        (S, S, 3) uint8, a new array.

    Example:
        >>> marked = mark_outside(np.full((4, 4, 3), 9, np.uint8), np.eye(4, dtype=bool), square=1)
        >>> marked[..., 0].tolist()
        [[255, 9, 9, 9], [9, 255, 9, 9], [9, 9, 255, 9], [9, 9, 9, 255]]
    """
    rows, cols = np.indices(outside.shape) // square
    checker = np.where((rows + cols) % 2 == 0, 255, 0).astype(np.uint8)
    return np.where(outside[..., None], checker[..., None], crop)
