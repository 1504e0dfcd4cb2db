"""Preparing any photo the way training saw objects: separate the object, crop it square, centre, resize.

The object is separated from its background by, in order of preference: a mask file, the image's alpha channel,
or a uniform background (estimated from the image border). Any size and mode is accepted: RGB, RGBA, grey,
palette, 16-bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image
from scipy import ndimage

from affnerf.data.crop import crop_object, object_bbox
from affnerf.data.images import open_image, to_rgb8
from affnerf.errors import input_error

#: Largest per-channel difference (0..1) from the background colour still counted as background.
BACKGROUND_TOLERANCE = 0.06
#: Smallest share of the image the object must cover.
MIN_OBJECT_FRACTION = 0.0005


@dataclass
class PreparedImage:
    """An input photo ready for the encoders.

    Attributes:
        crop: (S, S, 3) uint8 object-centred crop on the training background.
        mask: (H, W) bool object pixels of the original image.
        rgb: (H, W, 3) uint8 original image.
        bbox: (x0, y0, x1, y1) of the object in the original image.
        source: how the object was separated: ``mask``, ``alpha`` or ``uniform background``.
    """

    crop: np.ndarray
    mask: np.ndarray
    rgb: np.ndarray
    bbox: tuple[int, int, int, int]
    source: str


def border_color(rgb: np.ndarray, width: int = 2) -> np.ndarray:
    """(3,) median colour (0..1) of the image's outer ``width`` pixels: the background of a centred object."""
    border = np.concatenate(
        [rgb[:width].reshape(-1, 3), rgb[-width:].reshape(-1, 3), rgb[:, :width].reshape(-1, 3), rgb[:, -width:].reshape(-1, 3)]
    )
    return np.median(border, axis=0) / 255.0


def uniform_background_mask(rgb: np.ndarray, tolerance: float = BACKGROUND_TOLERANCE) -> np.ndarray:
    """(H, W) bool object mask of an image on a uniform background.

    Pixels differing from the border colour by more than ``tolerance`` in some channel are object; specks of
    a few pixels are removed, the object's own holes are kept (a pair of glasses is not a disc).
    """
    bg = border_color(rgb)
    diff = np.abs(rgb.astype(np.float64) / 255.0 - bg).max(axis=-1)
    mask = diff > tolerance
    labels, count = ndimage.label(mask)
    if count > 1:
        sizes = ndimage.sum(mask, labels, index=np.arange(1, count + 1))
        keep = np.flatnonzero(sizes >= max(4, 0.002 * sizes.max())) + 1
        mask = np.isin(labels, keep)
    return mask


def _mask_from_file(path: Path, size: tuple[int, int]) -> np.ndarray:
    image = open_image(path)
    if (image.width, image.height) != size:
        raise input_error(path, f"mask is {image.width}x{image.height}, the image {size[0]}x{size[1]}")
    if image.mode in ("RGBA", "LA"):
        return np.asarray(image.getchannel("A")) > 127
    grey = to_rgb8(image).mean(axis=-1)
    return grey > 127


def prepare_image(
    image: Path,
    crop_size: int,
    background: tuple[float, float, float] = (1.0, 1.0, 1.0),
    mask: Path | None = None,
) -> PreparedImage:
    """Load a photo and prepare it for the encoders.

    Args:
        image: the photo (any size and mode Pillow reads).
        crop_size: side of the encoder crop.
        background: the training background colour the crop is placed on.
        mask: optional mask image (white or opaque = object), same size as the photo.

    Raises:
        AffnerfError: naming the file, for a missing or unreadable image or mask, or an image with no object
            (blank, or one colour).
    """
    image = Path(image)
    pil = open_image(image)
    rgb = to_rgb8(pil)
    size = (rgb.shape[1], rgb.shape[0])
    if mask is not None:
        obj, source = _mask_from_file(Path(mask), size), "mask"
    elif pil.mode in ("RGBA", "LA", "PA") or (pil.mode == "P" and "transparency" in pil.info):
        alpha = np.asarray(pil.convert("RGBA").getchannel("A"))
        obj, source = alpha > 127, "alpha"
        if obj.all():  # an opaque alpha channel says nothing: fall back to the background
            obj, source = uniform_background_mask(rgb), "uniform background"
    else:
        obj, source = uniform_background_mask(rgb), "uniform background"
    if obj.mean() < MIN_OBJECT_FRACTION:
        what = "the mask is empty" if source == "mask" else "the image is blank or of one colour"
        raise input_error(mask if source == "mask" else image, f"no object found ({what})")
    bbox = object_bbox(obj)
    assert bbox is not None
    return PreparedImage(crop_object(rgb, obj, crop_size, background), obj, rgb, bbox, source)


def save_rgb(path: Path, image: np.ndarray) -> None:
    """Write a (H, W, 3) uint8 image as PNG."""
    Image.fromarray(np.ascontiguousarray(image)).save(path)
