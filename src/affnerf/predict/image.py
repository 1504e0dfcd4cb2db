"""Preparing any photo the way training saw objects: separate the object, crop it square, centre, resize.

The object is separated from its background by, in order of preference: a mask file, the image's alpha channel
(for ``segment="auto"``), or the separation method chosen with ``segment`` (:mod:`affnerf.predict.segment`:
``auto`` takes a uniform background when the border is of one colour, else the salient-object model). Any size
and mode is accepted: RGB, RGBA, grey, palette, 16-bit.

How well that went is measured (:class:`Separation`): the share of the image the object covers, the share of the
image's border it touches, for a uniform background the share of the border that is one colour and, when two
methods ran, their agreement (IoU). A separation by a uniform background on an image without one (noise, a
gradient, a cluttered scene), a mask that fills the frame or runs along its border, or two methods that disagree,
is doubtful: the model would be given a blob, so a warning says so and suggests ``--mask FILE``, and the
prediction goes on. An image with no object pixels at all (a blank or one-colour frame, an empty mask) is an error
instead (exit code 2): there is nothing to encode, any output would be invented, and scripts can skip such frames
by the exit code.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from affnerf.data.crop import crop_object, object_bbox, touches_border
from affnerf.data.images import open_image, to_rgb8
from affnerf.errors import input_error
from affnerf.predict.segment import (
    MIN_AGREEMENT,
    MIN_SEGMENTER_CONFIDENCE,
    Box,
    Segmentation,
    SegmentMethod,
    background_uniformity,
    border_pixels,
    segment,
)

#: Smallest share of the image the object must cover.
MIN_OBJECT_FRACTION = 0.0005
#: Smallest share of the border within ``BACKGROUND_TOLERANCE`` of its colour for a uniform background to be found
#: (an object touching the border lowers it too: that is judged by ``MAX_BORDER_CONTACT``).
MIN_BACKGROUND_UNIFORMITY = 0.5
#: Largest share of the image an object separated with confidence covers.
MAX_OBJECT_FRACTION = 0.9
#: Largest share of the image border an object separated with confidence touches.
MAX_BORDER_CONTACT = 0.25
#: Separations never doubted: the user's own statement of the object.
TRUSTED_SOURCES = ("mask", "whole image")

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Separation:
    """How the object was told from its background, and how confidently.

    Attributes:
        source: ``mask``, ``alpha``, ``uniform background``, ``segmenter``, ``salient``, ``grabcut`` or
            ``whole image``.
        object_fraction: share of the image's pixels that are object.
        border_contact: share of the image's border pixels (``BORDER_WIDTH`` wide) that are object.
        background_uniformity: for ``uniform background``, the share of the border pixels within
            ``BACKGROUND_TOLERANCE`` of the border colour (1 on a clean backdrop); ``None`` otherwise.
        problems: why the separation is doubtful, in a few words each; empty when it is confident.
        agreement: IoU of the two methods' masks when two ran (``None`` otherwise).
        compared_with: the second method (``None`` when one ran).
        note: why ``auto`` fell back from the salient model (``None`` otherwise).
        confidence: the object segmenter's mean probability over its mask (``None`` for other methods).
        box: the rectangle (x0, y0, x1, y1) the separation was confined to (``None``: the whole image).
        cut_off: the object reaches the image's edge, so the photo may not show all of it (never for ``whole
            image``, which is the image by definition).
    """

    source: str
    object_fraction: float
    border_contact: float
    background_uniformity: float | None
    problems: tuple[str, ...]
    agreement: float | None = None
    compared_with: str | None = None
    note: str | None = None
    confidence: float | None = None
    box: Box | None = None
    cut_off: bool = False

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
            "agreement": None if self.agreement is None else round(self.agreement, 4),
            "compared_with": self.compared_with,
            "segmenter_confidence": None if self.confidence is None else round(self.confidence, 4),
            "box": None if self.box is None else list(self.box),
            "note": self.note,
            "problems": list(self.problems),
            "cut_off": self.cut_off,
        }

    def warning(self, image: Path) -> str | None:
        """The one-line warning of a doubtful separation (``None`` when confident)."""
        if self.confident:
            return None
        return (
            f"{image}: the object could not be separated with confidence ({'; '.join(self.problems)}), so the "
            f"prediction may be a blob; give the object's mask with --mask FILE (white = object; the mask used is "
            f"written as mask.png to fix), or a photo of it on a plain background"
        )

    def cut_off_warning(self, image: Path) -> str | None:
        """The one-line warning of an object the photo may not show whole (``None`` when it does)."""
        if not self.cut_off:
            return None
        return (
            f"{image}: the object reaches the edge of the photo, so part of it may be cut off and the model will "
            f"guess the rest (from such views of test objects it predicts 0.035 mIoU worse than from whole views "
            f"of the same objects); a photo that shows the whole object with a margin around it is better"
        )


@dataclass
class PreparedImage:
    """An input photo ready for the encoders.

    Attributes:
        crop: (S, S, 3) uint8 object-centred crop on the training background.
        mask: (H, W) bool object pixels of the original image.
        rgb: (H, W, 3) uint8 original image.
        bbox: (x0, y0, x1, y1) of the object in the original image.
        separation: how the object was separated (``source``) and how confidently.
    """

    crop: np.ndarray
    mask: np.ndarray
    rgb: np.ndarray
    bbox: tuple[int, int, int, int]
    separation: Separation

    @property
    def source(self) -> str:
        """How the object was separated (see :attr:`Separation.source`)."""
        return self.separation.source


def separation_problems(
    object_fraction: float,
    border_contact: float,
    uniformity: float | None,
    agreement: float | None = None,
    confidence: float | None = None,
) -> tuple[str, ...]:
    """Why a separation with these measures is doubtful (empty when it is not).

    Example:
        >>> separation_problems(0.2, 0.0, 1.0)
        ()
        >>> separation_problems(0.95, 0.1, None)
        ('the object covers 95% of the image',)
        >>> separation_problems(0.2, 0.0, None, 0.5)
        ('two separation methods agree on only 50% (IoU) of the object',)
        >>> separation_problems(0.2, 0.0, None, confidence=0.6)
        ('the object segmenter is only 60% sure of its mask',)
    """
    problems = []
    if uniformity is not None and uniformity < MIN_BACKGROUND_UNIFORMITY:
        problems.append(f"no uniform background: {uniformity:.0%} of the image border is one colour")
    if object_fraction > MAX_OBJECT_FRACTION:
        problems.append(f"the object covers {object_fraction:.0%} of the image")
    if border_contact > MAX_BORDER_CONTACT:
        problems.append(f"the object touches {border_contact:.0%} of the image border")
    if agreement is not None and agreement < MIN_AGREEMENT:
        problems.append(f"two separation methods agree on only {agreement:.0%} (IoU) of the object")
    if confidence is not None and confidence < MIN_SEGMENTER_CONFIDENCE:
        problems.append(f"the object segmenter is only {confidence:.0%} sure of its mask")
    return tuple(problems)


def measure_separation(rgb: np.ndarray, mask: np.ndarray, source: str, seg: Segmentation | None = None) -> Separation:
    """How confidently the (H, W) bool ``mask`` separates the object in the (H, W, 3) uint8 image.

    A mask file or the whole image (``--segment none``) is the user's own statement of the object and is never
    doubted; other separations are doubtful when the object fills the frame or runs along its border, a uniform
    background also when the border is not of one colour, two methods (``seg.agreement``) when they disagree, and
    the object segmenter when it is unsure of its mask (``seg.confidence``).
    """
    fraction, contact = float(mask.mean()), float(border_pixels(mask).mean())
    uniformity = background_uniformity(rgb) if source == "uniform background" else None
    agreement, compared, note = (seg.agreement, seg.compared_with, seg.note) if seg else (None, None, None)
    confidence, box = (seg.confidence, seg.box) if seg else (None, None)
    problems = (
        () if source in TRUSTED_SOURCES else separation_problems(fraction, contact, uniformity, agreement, confidence)
    )
    cut = source != "whole image" and bool(touches_border(mask))
    return Separation(source, fraction, contact, uniformity, problems, agreement, compared, note, confidence, box, cut)


def _mask_from_file(path: Path, size: tuple[int, int]) -> np.ndarray:
    image = open_image(path)
    if (image.width, image.height) != size:
        raise input_error(path, f"mask is {image.width}x{image.height}, the image {size[0]}x{size[1]}")
    if image.mode in ("RGBA", "LA"):
        return np.asarray(image.getchannel("A")) > 127
    grey = to_rgb8(image).mean(axis=-1)
    return grey > 127


def _has_alpha(pil: Image.Image) -> bool:
    return pil.mode in ("RGBA", "LA", "PA") or (pil.mode == "P" and "transparency" in pil.info)


def separate(
    pil: Image.Image,
    rgb: np.ndarray,
    image: Path,
    mask: Path | None,
    method: str,
    segmenter: Path | None = None,
    box: Box | None = None,
) -> Segmentation:
    """The object mask of a photo: the mask file, else (for ``auto``) its alpha channel unless opaque, else
    :func:`affnerf.predict.segment.segment` with ``method`` (inside ``box`` when given)."""
    if mask is not None:
        return Segmentation(_mask_from_file(Path(mask), (rgb.shape[1], rgb.shape[0])), "mask")
    if method == "auto" and _has_alpha(pil):
        alpha = np.asarray(pil.convert("RGBA").getchannel("A")) > 127
        if not alpha.all():  # an opaque alpha channel says nothing
            return Segmentation(alpha, "alpha")
    return segment(rgb, method, str(image), segmenter, box)


def prepare_image(
    image: Path,
    crop_size: int,
    background: tuple[float, float, float] = (1.0, 1.0, 1.0),
    mask: Path | None = None,
    segment: SegmentMethod = "auto",
    segmenter: Path | None = None,
    box: Box | None = None,
    outside: str = "background",
) -> PreparedImage:
    """Load a photo and prepare it for the encoders.

    Args:
        image: the photo (any size and mode Pillow reads).
        crop_size: side of the encoder crop.
        background: the training background colour the crop is placed on.
        mask: optional mask image (white or opaque = object), same size as the photo; it overrides ``segment``.
        segment: how to separate the object without a mask (:data:`affnerf.predict.segment.SEGMENT_METHODS`):
            ``auto`` (alpha, else a uniform background, else the object segmenter, else the salient model),
            ``segmenter``, ``salient``, ``grabcut``, ``uniform`` or ``none`` (the whole image is the object).
        segmenter: an object segmenter file (``affnerf train-segmenter``) for ``segmenter``, and for ``auto``
            before the salient model; ``None`` for the shipped one, ``segment.NO_SEGMENTER`` for none.
        box: confine the separation to this rectangle (x0, y0, x1, y1).
        outside: the model's ``crop_outside``: ``checker`` marks where the crop leaves the photo.

    Logs a one-line warning naming the image when the separation is doubtful (see :class:`Separation`), else when
    the object reaches the image's edge (``Separation.cut_off``), and when ``auto`` falls back because the optional
    salient model is not installed.

    Raises:
        AffnerfError: naming the file, for a missing or unreadable image or mask, or an image with no object
            (blank, or one colour; an empty mask): see the module's notes on why that is an error; for
            ``segment="salient"`` or ``"grabcut"`` without the optional extra ``affnerf[segment]``; a ``box`` that
            holds no pixel of the image.
    """
    image = Path(image)
    pil = open_image(image)
    rgb = to_rgb8(pil)
    seg = separate(pil, rgb, image, mask, segment, segmenter, box)
    obj, source = seg.mask, seg.source
    if obj.mean() < MIN_OBJECT_FRACTION:
        what = "the mask is empty" if source == "mask" else "the image is blank or of one colour"
        fix = "give a mask with white object pixels" if source == "mask" else "give a photo of an object"
        raise input_error(mask if source == "mask" else image, f"no object found ({what}); {fix}")
    bbox = object_bbox(obj)
    assert bbox is not None
    separation = measure_separation(rgb, obj, source, seg)
    warning = separation.warning(image) or separation.cut_off_warning(image)  # a doubtful mask's line comes first
    if warning:
        logger.warning("%s", warning)
    return PreparedImage(crop_object(rgb, obj, crop_size, background, outside=outside), obj, rgb, bbox, separation)


def save_mask(path: Path, mask: np.ndarray) -> None:
    """Write an (H, W) bool mask as an 8-bit PNG, white = object (what ``--mask`` reads back)."""
    Image.fromarray(mask.astype(np.uint8) * 255).save(path)


def save_rgb(path: Path, image: np.ndarray) -> None:
    """Write a (H, W, 3) uint8 image as PNG."""
    Image.fromarray(np.ascontiguousarray(image)).save(path)
