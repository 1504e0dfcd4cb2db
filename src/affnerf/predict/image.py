"""Preparing any photo the way training saw objects: separate the object, crop it square, centre, resize.

The object is separated from its background by, in order of preference: a mask file, the image's alpha channel,
or a uniform background (estimated from the image border). Any size and mode is accepted: RGB, RGBA, grey,
palette, 16-bit.

How well that went is measured (:class:`Separation`): the share of the image the object covers, the share of the
image's border it touches and, for a uniform background, the share of the border that is one colour. An image
without a uniform background (noise, a gradient, a cluttered scene), or whose "object" fills the frame or runs
along its border, is separated doubtfully: the model would be given a blob, so a warning says so and suggests
``--mask FILE``, and the prediction goes on. An image with no object pixels at all (a blank or one-colour frame,
an empty mask) is an error instead (exit code 2): there is nothing to encode, any output would be invented, and
scripts can skip such frames by the exit code.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

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
#: Width in pixels of the image border the background colour and the object's border contact are measured on.
BORDER_WIDTH = 2
#: Smallest share of the border within ``BACKGROUND_TOLERANCE`` of its colour for a uniform background to be found
#: (an object touching the border lowers it too: that is judged by ``MAX_BORDER_CONTACT``).
MIN_BACKGROUND_UNIFORMITY = 0.5
#: Largest share of the image an object separated with confidence covers.
MAX_OBJECT_FRACTION = 0.9
#: Largest share of the image border an object separated with confidence touches.
MAX_BORDER_CONTACT = 0.25

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Separation:
    """How the object was told from its background, and how confidently.

    Attributes:
        source: ``mask``, ``alpha`` or ``uniform background``.
        object_fraction: share of the image's pixels that are object.
        border_contact: share of the image's border pixels (``BORDER_WIDTH`` wide) that are object.
        background_uniformity: for ``uniform background``, the share of the border pixels within
            ``BACKGROUND_TOLERANCE`` of the border colour (1 on a clean backdrop); ``None`` otherwise.
        problems: why the separation is doubtful, in a few words each; empty when it is confident.
    """

    source: str
    object_fraction: float
    border_contact: float
    background_uniformity: float | None
    problems: tuple[str, ...]

    @property
    def confident(self) -> bool:
        return not self.problems

    def to_json(self) -> dict[str, Any]:
        """The ``separation`` entry of ``prediction.json``."""
        uniformity = None if self.background_uniformity is None else round(self.background_uniformity, 4)
        return {
            "source": self.source,
            "confident": self.confident,
            "object_fraction": round(self.object_fraction, 4),
            "border_contact": round(self.border_contact, 4),
            "background_uniformity": uniformity,
            "problems": list(self.problems),
        }

    def warning(self, image: Path) -> str | None:
        """The one-line warning of a doubtful separation (``None`` when confident)."""
        if self.confident:
            return None
        return (
            f"{image}: the object could not be separated with confidence ({'; '.join(self.problems)}), so the "
            f"prediction may be a blob; give the object's mask with --mask FILE (white = object), or a photo of it "
            f"on a plain background"
        )


@dataclass
class PreparedImage:
    """An input photo ready for the encoders.

    Attributes:
        crop: (S, S, 3) uint8 object-centred crop on the training background.
        mask: (H, W) bool object pixels of the original image.
        rgb: (H, W, 3) uint8 original image.
        bbox: (x0, y0, x1, y1) of the object in the original image.
        separation: how the object was separated (``source``: ``mask``, ``alpha`` or ``uniform background``) and
            how confidently.
    """

    crop: np.ndarray
    mask: np.ndarray
    rgb: np.ndarray
    bbox: tuple[int, int, int, int]
    separation: Separation

    @property
    def source(self) -> str:
        """How the object was separated: ``mask``, ``alpha`` or ``uniform background``."""
        return self.separation.source


def border_pixels(image: np.ndarray, width: int = BORDER_WIDTH) -> np.ndarray:
    """(N, ...) the values of the image's outer ``width`` pixels (H, W, ...), the corners counted twice.

    Example:
        >>> border_pixels(np.arange(9).reshape(3, 3), 1).tolist()
        [0, 1, 2, 6, 7, 8, 0, 3, 6, 2, 5, 8]
    """
    rest = image.shape[2:]
    parts = [image[:width], image[-width:], image[:, :width], image[:, -width:]]
    return np.concatenate([p.reshape(-1, *rest) for p in parts])


def border_color(rgb: np.ndarray, width: int = BORDER_WIDTH) -> np.ndarray:
    """(3,) median colour (0..1) of the image's outer ``width`` pixels: the background of a centred object."""
    return np.median(border_pixels(rgb, width), axis=0) / 255.0


def background_uniformity(rgb: np.ndarray, tolerance: float = BACKGROUND_TOLERANCE) -> float:
    """Share of the (H, W, 3) uint8 image's border pixels within ``tolerance`` (per channel, 0..1) of the border
    colour: 1 on a uniform backdrop, near 0 on noise or a gradient."""
    border = border_pixels(rgb).astype(np.float64) / 255.0
    return float((np.abs(border - border_color(rgb)).max(axis=-1) <= tolerance).mean())


def separation_problems(object_fraction: float, border_contact: float, uniformity: float | None) -> tuple[str, ...]:
    """Why a separation with these measures is doubtful (empty when it is not).

    Example:
        >>> separation_problems(0.2, 0.0, 1.0)
        ()
        >>> separation_problems(0.95, 0.1, None)
        ('the object covers 95% of the image',)
    """
    problems = []
    if uniformity is not None and uniformity < MIN_BACKGROUND_UNIFORMITY:
        problems.append(f"no uniform background: {uniformity:.0%} of the image border is one colour")
    if object_fraction > MAX_OBJECT_FRACTION:
        problems.append(f"the object covers {object_fraction:.0%} of the image")
    if border_contact > MAX_BORDER_CONTACT:
        problems.append(f"the object touches {border_contact:.0%} of the image border")
    return tuple(problems)


def measure_separation(rgb: np.ndarray, mask: np.ndarray, source: str) -> Separation:
    """How confidently the (H, W) bool ``mask`` separates the object in the (H, W, 3) uint8 image.

    A mask file is the user's own statement of the object and is never doubted; alpha and uniform background
    separations are doubtful when the object fills the frame or runs along its border, and a uniform background
    also when the border is not of one colour.
    """
    fraction, contact = float(mask.mean()), float(border_pixels(mask).mean())
    uniformity = background_uniformity(rgb) if source == "uniform background" else None
    problems = () if source == "mask" else separation_problems(fraction, contact, uniformity)
    return Separation(source, fraction, contact, uniformity, problems)


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

    Logs a one-line warning naming the image when the separation is doubtful (see :class:`Separation`).

    Raises:
        AffnerfError: naming the file, for a missing or unreadable image or mask, or an image with no object
            (blank, or one colour; an empty mask): see the module's notes on why that is an error.
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
        fix = "give a mask with white object pixels" if source == "mask" else "give a photo of an object"
        raise input_error(mask if source == "mask" else image, f"no object found ({what}); {fix}")
    bbox = object_bbox(obj)
    assert bbox is not None
    separation = measure_separation(rgb, obj, source)
    if not separation.confident:
        logger.warning("%s", separation.warning(image))
    return PreparedImage(crop_object(rgb, obj, crop_size, background), obj, rgb, bbox, separation)


def save_rgb(path: Path, image: np.ndarray) -> None:
    """Write a (H, W, 3) uint8 image as PNG."""
    Image.fromarray(np.ascontiguousarray(image)).save(path)
