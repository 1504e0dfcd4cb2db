"""Separating the object of a photo from its background: the methods of ``affnerf predict --segment``.

- ``uniform``: the object is what differs from the colour of the image border (a clean backdrop).
- ``grabcut``: OpenCV's GrabCut, started from a centred rectangle (the object is assumed inside it).
- ``segmenter``: an object segmenter (:mod:`affnerf.model.segmenter`): the one that ships with affnerf (U²-Net-p
  fine-tuned to find the procedural families among clutter, :func:`affnerf.predict.shipped.shipped_segmenter`),
  or one trained on your own object families with ``affnerf train-segmenter`` and given as a file, reading the
  whole photo and its four corner tiles (:func:`~affnerf.model.segmenter.photo_probability`); its main region,
  redrawn by GrabCut from the network's probabilities when OpenCV is there. Its confidence is the mean
  probability it gives the pixels of its own mask; below :data:`MIN_SEGMENTER_CONFIDENCE` the separation is
  doubtful.
- ``salient``: the U²-Net-p salient-object model (:mod:`affnerf.predict.salient`), largest connected component.
- ``auto`` (the default): a uniform background when the border is of one colour (:data:`AUTO_UNIFORMITY`), else
  the object segmenter (the given file, else the shipped one) when it finds something, else the salient model;
  without the optional extra ``affnerf[segment]`` that last step falls back to GrabCut (OpenCV) or the uniform
  estimate, with one warning line. When the salient model ran and OpenCV is there, GrabCut from the centred
  rectangle also runs, and the two masks' IoU is the ``agreement`` recorded with the separation; when they disagree
  (IoU < :data:`MIN_AGREEMENT`), ``auto`` takes GrabCut's mask, and the separation is doubtful. ``segmenter=
  NO_SEGMENTER`` (``--segmenter none``) leaves the object segmenter out.
- ``none``: the whole image is the object.

With a box (``--box X0 Y0 X1 Y1``, the rectangle of the photo the object lies in, as a detector or a click-and-drag
gives it), the method runs on the box alone, as on a photo of its own, and everything outside it is background;
``auto`` takes GrabCut from the rectangle :data:`BOX_MARGIN` inside the box, unless the box's border is of one
colour (then the uniform background inside it).

A given ``--mask`` and (for ``auto``) the image's alpha channel come first: see :func:`affnerf.predict.image.
prepare_image`. OpenCV (``opencv-python-headless``) and onnxruntime are optional and imported only when used.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal, get_args

import numpy as np
from scipy import ndimage

from affnerf.data.composite import largest_component
from affnerf.errors import AffnerfError
from affnerf.model.segmenter import load_segmenter, mask_confidence, photo_probability, probability_mask
from affnerf.predict import shipped
from affnerf.predict.grabcut import grabcut_mask, opencv, refine_with_grabcut
from affnerf.predict.salient import SalientUnavailable, load_salient_model, salient_mask

#: The separation methods of ``--segment``.
SegmentMethod = Literal["auto", "segmenter", "salient", "grabcut", "uniform", "none"]
SEGMENT_METHODS: tuple[str, ...] = get_args(SegmentMethod)
#: The rectangle of a photo the object lies in: (x0, y0, x1, y1) in pixels, x to the right and y down from the
#: top-left corner, x1 and y1 exclusive.
Box = tuple[int, int, int, int]
#: Largest per-channel difference (0..1) from the background colour still counted as background.
BACKGROUND_TOLERANCE = 0.06
#: Width in pixels of the image border the background colour and the object's border contact are measured on.
BORDER_WIDTH = 2
#: Smallest share of the border within ``BACKGROUND_TOLERANCE`` of its colour for ``auto`` to take the background
#: as uniform: a clean render has 1; on the composite benchmark a dark star field had 0.83-0.91 and its "uniform"
#: mask kept the stars (IoU 0.41 against 0.83 by the salient model), other photographs 0-0.46.
AUTO_UNIFORMITY = 0.97
#: The margin inside a ``--box`` (share of each side) GrabCut starts from (its image is the box). Chosen on
#: composites of another seed than the benchmark's (``bench_segment.py --seed 1``): the centred rectangle 0, 2, 4
#: or 8 % inside boxes 0-5 % larger than the object per side gave a mean mask IoU of 0.87, 0.90, 0.83 and 0.64;
#: inside boxes 5-25 % larger, 1, 2, 4 and 8 % gave 0.88, 0.87, 0.88 and 0.90. A detector's tight box needs a
#: small margin, and a loose drawn one hardly minds.
BOX_MARGIN = 0.02
#: Smallest confidence of the object segmenter's mask cut to a ``--box`` for ``auto`` to take it instead of
#: GrabCut in the box. Chosen on composites of another seed than the benchmark's (``segment_box_rule.py --seed
#: 1``) for the shipped two-network ensemble, its mask redrawn by GrabCut from its probabilities: 0.7, 0.75, 0.8,
#: 0.85 and 0.9 gave a mean mask IoU of 0.911, 0.902, 0.921, 0.909 and 0.903 in boxes 5-25 % larger than the
#: object per side (GrabCut alone 0.871, the segmenter's mask alone 0.899), and 0.919, 0.919, 0.941, 0.915 and
#: 0.911 in boxes 0-5 % larger (0.881, 0.899); without the redrawing 0.8 was the best too (0.909 and 0.930). (The
#: single network shipped before chose 0.85.) Run on the box as on a photo of its own, the segmenter was worse than
#: GrabCut (0.54 and 0.19): it sees objects at the size they have in a photo. Rechecked with the tiles on seeds 1 and
#: 2: 0.8 is within 0.003 of the best threshold over the four (seed, box) sets (benchmarks/results/segmenter_u2netp.md).
BOX_SEGMENTER_CONFIDENCE = 0.8
#: Smallest side in pixels of a ``--box`` (after clipping to the image): a narrower one cannot hold an object and
#: its background (GrabCut needs pixels of both; one 2 pixels wide crashed OpenCV before this check).
MIN_BOX_SIDE = 8
#: Smallest IoU of two methods' masks (when two ran) for a confident separation. On the composite benchmark, masks
#: of the salient model agreeing this well with GrabCut's had a mean IoU of 0.84 with the truth; 92 % of the bad
#: ones (IoU < 0.5) agreed less.
MIN_AGREEMENT = 0.8
#: Whether ``auto`` and ``salient`` redraw the salient mask's edges with GrabCut from its trimap: on the composite
#: benchmark it raised the mean mask IoU from 0.483 to 0.490 (better in most composites) for about 0.25 s an image.
REFINE_SALIENT = True
#: Whether the object segmenter's mask is redrawn by GrabCut from the network's probabilities
#: (:func:`affnerf.predict.grabcut.probability_trimap`). On the composite benchmark's 240 composites of seeds 0-4
#: it raised the mean mask IoU of the shipped segmenter's mask from 0.847 to 0.869 (gains on every seed, most on
#: eyeglasses and scissors) for about 0.27 s an image (``benchmarks/results/segmenter_u2netp.md``, "GrabCut guided
#: by the segmenter's probabilities"); GrabCut from the mask's plain trimap gave 0.852.
REFINE_SEGMENTER = True
#: Smallest mean probability of the segmenter over its own mask for a confident separation.
MIN_SEGMENTER_CONFIDENCE = 0.8
#: How to get an object segmenter (the words of the error when one is needed and not given).
TRAIN_HINT = "train one on your objects with `affnerf train-segmenter --data DATA --out FILE` and pass --segmenter FILE"
#: The ``segmenter`` argument (``--segmenter none``) that leaves the object segmenter out, shipped one included.
NO_SEGMENTER = Path("none")
#: The ``segmenter`` argument (``--segmenter shipped``, the command's default; ``None`` in Python) for the shipped one.
SHIPPED_SEGMENTER = Path("shipped")

logger = logging.getLogger(__name__)


@dataclass
class Segmentation:
    """An object mask and how it was made.

    Attributes:
        mask: (H, W) bool object pixels.
        source: ``uniform background``, ``grabcut``, ``salient`` or ``whole image``.
        agreement: IoU of the masks of two methods, when two ran (``None`` otherwise).
        compared_with: the second method (``None`` when one ran).
        note: why ``auto`` did not use the salient model when it wanted to (``None`` otherwise).
        confidence: the object segmenter's mean probability over its mask (``None`` for other methods).
        box: the rectangle the separation was confined to, clipped to the image (``None``: the whole image).
    """

    mask: np.ndarray
    source: str
    agreement: float | None = None
    compared_with: str | None = None
    note: str | None = None
    confidence: float | None = None
    box: Box | None = None


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


def mask_iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two bool masks (1 when both are empty).

    Example:
        >>> mask_iou(np.array([1, 1, 0], bool), np.array([0, 1, 1], bool))
        0.3333333333333333
    """
    union = np.logical_or(a, b).sum()
    return float(np.logical_and(a, b).sum() / union) if union else 1.0


def salient_segmentation(rgb: np.ndarray, model=None, use_grabcut_on_disagreement: bool = False) -> Segmentation:
    """The salient model's mask (largest component; its edges redrawn by GrabCut when ``REFINE_SALIENT``) and,
    with OpenCV, its agreement (IoU) with GrabCut's own mask from the centred rectangle: two methods that share
    nothing, so when they disagree one of them is wrong. With ``use_grabcut_on_disagreement`` (``auto``), an
    agreement below ``MIN_AGREEMENT`` gives GrabCut's mask instead (better in 18 of the benchmark's 32 such
    composites).

    Raises:
        SalientUnavailable: the optional extra is not installed (and ``model`` not given).
    """
    model = model if model is not None else load_salient_model()
    mask = largest_component(salient_mask(model, rgb))
    if opencv() is None or not mask.any():
        return Segmentation(mask, "salient")
    if REFINE_SALIENT:
        mask = refine_with_grabcut(rgb, mask)
    other = grabcut_mask(rgb)
    agreement = mask_iou(mask, other)
    if use_grabcut_on_disagreement and agreement < MIN_AGREEMENT:
        return Segmentation(other, "grabcut", agreement, "salient")
    return Segmentation(mask, "salient", agreement, "grabcut")


def segmenter_segmentation(rgb: np.ndarray, model, box: Box | None = None, redraw_from: float = 0.0) -> Segmentation:
    """The object segmenter's mask (:func:`~affnerf.model.segmenter.probability_mask` of its map of the photo and of
    the photo's tiles, :func:`~affnerf.model.segmenter.photo_probability`; inside ``box`` only when one is given,
    the network still seeing the whole photo) and its confidence, the mean probability over that mask (0
    when it is empty). With OpenCV, when :data:`REFINE_SEGMENTER` and the confidence is at least ``redraw_from``
    (a caller that drops less sure masks spares their GrabCut), GrabCut then redraws the mask from the network's
    probabilities (:func:`~affnerf.predict.grabcut.refine_with_grabcut`, inside the box); the confidence stays the
    network's."""
    prob = photo_probability(model, rgb)
    inside = None
    if box is not None:
        x0, y0, x1, y1 = box
        inside = np.zeros(prob.shape, bool)
        inside[y0:y1, x0:x1] = True
    mask = probability_mask(prob, inside)
    confidence = mask_confidence(prob, mask)
    if REFINE_SEGMENTER and mask.any() and confidence >= redraw_from and opencv() is not None:
        mask = refine_with_grabcut(rgb, mask, prob, inside)
    return Segmentation(mask, "segmenter", confidence=confidence, box=box)


def resolve_segmenter(segmenter: Path | None) -> Path | None:
    """The object segmenter file to use: ``segmenter`` itself, the shipped one for ``None`` or
    :data:`SHIPPED_SEGMENTER` (``None`` when none is installed), and ``None`` for :data:`NO_SEGMENTER`."""
    if segmenter is None or Path(segmenter) == SHIPPED_SEGMENTER:
        return shipped.shipped_segmenter()
    return None if Path(segmenter) == NO_SEGMENTER else Path(segmenter)


def _fallback(rgb: np.ndarray, err: SalientUnavailable, name: str) -> Segmentation:
    """``auto`` without the salient model: GrabCut when OpenCV is there, else the uniform estimate."""
    use_grabcut = opencv() is not None
    instead = "GrabCut" if use_grabcut else "the image border's colour (expect a poor mask on a cluttered photo)"
    note = f"{err}; separated with {instead} instead"
    logger.warning("%s: %s", name, note)
    if use_grabcut:
        return Segmentation(grabcut_mask(rgb), "grabcut", note=note)
    return Segmentation(uniform_background_mask(rgb), "uniform background", note=note)


def clip_box(box: Box, shape: tuple[int, ...]) -> Box | None:
    """``box`` clipped to an image of ``shape`` (H, W, ...); ``None`` when no pixel of the image is left in it.

    Example:
        >>> clip_box((-5, 10, 50, 400), (300, 400)), clip_box((10, 10, 10, 20), (300, 400))
        ((0, 10, 50, 300), None)
    """
    h, w = shape[:2]
    x0, y0, x1, y1 = max(0, box[0]), max(0, box[1]), min(w, box[2]), min(h, box[3])
    return (x0, y0, x1, y1) if x0 < x1 and y0 < y1 else None


def segment_in_box(
    rgb: np.ndarray, box: Box, method: str = "auto", name: str = "image", segmenter: Path | None = None
) -> Segmentation:
    """Separate the object inside ``box`` only (everything outside is background). When the box's border is not of
    one colour, ``auto`` takes the object segmenter's mask cut to the box (:func:`segmenter_segmentation`, the
    network seeing the whole photo) if it is at least :data:`BOX_SEGMENTER_CONFIDENCE` sure of it, else GrabCut
    from the rectangle :data:`BOX_MARGIN` inside the box (when OpenCV is there); other methods run on the box as
    on a photo of its own.

    Raises:
        AffnerfError: naming the image, when the box holds none of its pixels or is narrower than
            :data:`MIN_BOX_SIDE` inside it; as :func:`segment`.
    """
    clipped = clip_box(box, rgb.shape)
    if clipped is None:
        h, w = rgb.shape[:2]
        raise AffnerfError(
            f"{name}: --box {' '.join(map(str, box))} holds no pixel of the {w}x{h} image: give X0 Y0 X1 Y1 in "
            f"pixels with 0 <= X0 < X1 <= {w} and 0 <= Y0 < Y1 <= {h}"
        )
    x0, y0, x1, y1 = clipped
    if min(x1 - x0, y1 - y0) < MIN_BOX_SIDE:
        raise AffnerfError(
            f"{name}: --box {' '.join(map(str, box))} is {x1 - x0}x{y1 - y0} pixels inside the image, too small to "
            f"hold an object (at least {MIN_BOX_SIDE} pixels a side): give the rectangle around the whole object"
        )
    sub = np.ascontiguousarray(rgb[y0:y1, x0:x1])
    cluttered = method == "auto" and background_uniformity(sub) < AUTO_UNIFORMITY
    found = resolve_segmenter(segmenter) if cluttered else None
    if found is not None:
        seg = segmenter_segmentation(rgb, load_segmenter(found), clipped, BOX_SEGMENTER_CONFIDENCE)
        if seg.confidence >= BOX_SEGMENTER_CONFIDENCE:
            return seg
    if cluttered and opencv() is not None:
        seg = Segmentation(grabcut_mask(sub, BOX_MARGIN), "grabcut")
    else:
        seg = segment(sub, method, name, segmenter)
    mask = np.zeros(rgb.shape[:2], bool)
    mask[y0:y1, x0:x1] = seg.mask
    return replace(seg, mask=mask, box=clipped)


def segment(
    rgb: np.ndarray,
    method: str = "auto",
    name: str = "image",
    segmenter: Path | None = None,
    box: Box | None = None,
) -> Segmentation:
    """Separate the object of an (H, W, 3) uint8 photo with ``method`` (one of :data:`SEGMENT_METHODS`).

    ``name`` (the photo's path) starts the fallback warning of ``auto``; ``segmenter`` is an object segmenter file
    (``affnerf train-segmenter``) for ``segmenter`` and ``auto``, ``None`` for the shipped one, or
    :data:`NO_SEGMENTER`; ``box`` confines the separation to a rectangle (:func:`segment_in_box`).

    Raises:
        AffnerfError: an unknown method; ``salient`` without the optional extra, ``grabcut`` without OpenCV,
            each naming what to install; ``segmenter`` with no segmenter to use, or a file that is not one; a box
            outside the image or too small to hold an object (exit code 2).
    """
    if method not in SEGMENT_METHODS:
        raise AffnerfError(f"unknown separation method {method!r}: choose one of {', '.join(SEGMENT_METHODS)}")
    if box is not None:
        return segment_in_box(rgb, box, method, name, segmenter)
    if method == "none":
        return Segmentation(np.ones(rgb.shape[:2], bool), "whole image")
    if method == "uniform" or (method == "auto" and background_uniformity(rgb) >= AUTO_UNIFORMITY):
        return Segmentation(uniform_background_mask(rgb), "uniform background")
    if method == "grabcut":
        return Segmentation(grabcut_mask(rgb), "grabcut")
    found = resolve_segmenter(segmenter) if method in ("segmenter", "auto") else None
    if method == "segmenter" and found is None:
        raise AffnerfError(f"--segment segmenter needs a segmenter file (none is installed): {TRAIN_HINT}")
    if found is not None:
        seg = segmenter_segmentation(rgb, load_segmenter(found))
        if method == "segmenter" or seg.mask.any():
            return seg
    try:
        seg = salient_segmentation(rgb, use_grabcut_on_disagreement=method == "auto")
    except SalientUnavailable as err:
        if method == "salient":
            raise
        return _fallback(rgb, err, name)
    if method == "auto" and not seg.mask.any():  # nothing stands out (noise, a gradient): judged by its border
        note = "neither the salient model nor GrabCut found an object; separated by the image border's colour"
        return Segmentation(uniform_background_mask(rgb), "uniform background", note=note)
    return seg
