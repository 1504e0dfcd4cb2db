"""GrabCut (OpenCV's graph-cut segmentation with colour models) for ``affnerf predict --segment``: from a rectangle
the object is assumed inside, or from a trimap that redraws the edges of a mask another method made.

A trimap labels every pixel with one of OpenCV's four GrabCut classes: 0 sure background (``GC_BGD``), 1 sure
object (``GC_FGD``), 2 probably background (``GC_PR_BGD``), 3 probably object (``GC_PR_FGD``). GrabCut keeps the
sure pixels and decides the unsure ones from colour models learnt on the image. OpenCV
(``opencv-python-headless``) is optional and imported only when used.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from affnerf.data.composite import largest_component
from affnerf.errors import AffnerfError
from affnerf.predict.salient import INSTALL_HINT

#: GrabCut: iterations, the rectangle's margin (share of each side left out as sure background), the largest image
#: side it works at (larger photos are reduced, and the mask brought back).
GRABCUT_ITERATIONS, GRABCUT_MARGIN, GRABCUT_MAX_SIDE = 5, 0.04, 400
#: Seed of OpenCV's random generator, set before each GrabCut: its colour models start from k-means++ drawn from
#: that process-wide generator, so without it a photo's mask depended on how many GrabCuts ran before (on the
#: composite benchmark GrabCut's mean mask IoU moved between 0.546 and 0.560 from one run to the next; it is
#: 0.538 with this seed, a draw like the others, not a choice).
GRABCUT_SEED = 0
#: Half-width of the unsure band of a trimap made from a mask, as a share of the image's larger side.
TRIMAP_BAND = 0.02
#: :func:`probability_trimap`: the half-width of its unsure band (share of the image's larger side) and the largest
#: probability outside the band for a sure background pixel. Chosen on the composite benchmark's seeds 1 and 2 and
#: checked on seeds 0, 3 and 4 (``benchmarks/segment_refine.py``; ``benchmarks/results/segmenter_u2netp.md``,
#: "GrabCut guided by the segmenter's probabilities").
PROBABILITY_TRIMAP_BAND, PROBABILITY_SURE_BACKGROUND = 0.06, 0.05
#: :func:`probability_trimap`: the mask's thin parts (those a disc of this radius, a share of the image's larger
#: side, does not fit in: under about 10 px across in a 400 px photo) are sure object where the map gives them at
#: least :data:`PROBABILITY_SURE_OBJECT`. Without it a thin part had no sure pixel (the band's erosion leaves none),
#: and on a busy photograph GrabCut's colour models gave a screwdriver's shaft or a temple of eyeglasses to the
#: background. Only thin parts: made sure everywhere in the mask, the map's filled-in holes (a scissors' rings, under
#: a bucket's bail) could not be reopened. Chosen on the composite benchmark's seeds 1 and 2 (radius 0.0075 / 0.0125
#: / 0.02 × probability 0.8 / 0.9, and the whole mask at 0.7-0.98) and checked on seeds 0 and 3-5: mean redrawn mask
#: IoU 0.8907 → 0.8958 on those 192 composites (``benchmarks/segment_thresholds.py``;
#: ``benchmarks/results/segmenter_u2netp.md``, "Sure thin parts").
PROBABILITY_THIN_RADIUS, PROBABILITY_SURE_OBJECT = 0.0125, 0.8


def opencv():
    """The ``cv2`` module, or ``None`` when opencv-python-headless is not installed."""
    try:
        import cv2
    except ImportError:
        return None
    return cv2


def grabcut_labels(rgb: np.ndarray, labels: np.ndarray | None, margin: float = GRABCUT_MARGIN) -> np.ndarray:
    """Run GrabCut on the (H, W, 3) image, from ``labels`` (an (H, W) uint8 trimap, see the module) or, when
    ``None``, from the centred rectangle ``margin`` (share of each side) inside the image's edges; returns the
    (H, W) bool object pixels.

    Raises:
        AffnerfError: OpenCV is not installed, naming what to install.
    """
    cv2 = opencv()
    if cv2 is None:
        raise AffnerfError(f"GrabCut needs OpenCV (opencv-python-headless), which is not installed: {INSTALL_HINT}")
    h, w = rgb.shape[:2]
    scale = min(1.0, GRABCUT_MAX_SIDE / max(h, w))
    size = (max(1, round(w * scale)), max(1, round(h * scale)))
    bgr = np.ascontiguousarray(cv2.resize(rgb, size, interpolation=cv2.INTER_AREA)[..., ::-1])
    bgd, fgd = np.zeros((1, 65), np.float64), np.zeros((1, 65), np.float64)
    cv2.setRNGSeed(GRABCUT_SEED)
    if labels is None:
        gc = np.zeros(bgr.shape[:2], np.uint8)
        mx, my = max(1, round(margin * size[0])), max(1, round(margin * size[1]))
        rect = (mx, my, size[0] - 2 * mx, size[1] - 2 * my)
        if min(rect[2:]) < 1:  # an image of 2 pixels or fewer a side leaves no object pixel to start from
            return np.zeros((h, w), bool)
        cv2.grabCut(bgr, gc, rect, bgd, fgd, GRABCUT_ITERATIONS, cv2.GC_INIT_WITH_RECT)
    else:
        gc = np.ascontiguousarray(cv2.resize(labels, size, interpolation=cv2.INTER_NEAREST))
        if (gc % 2 == 1).all() or (gc % 2 == 0).all():  # GC_FGD, GC_PR_FGD are odd: nothing to separate
            return labels % 2 == 1
        cv2.grabCut(bgr, gc, None, bgd, fgd, GRABCUT_ITERATIONS, cv2.GC_INIT_WITH_MASK)
    obj = (gc % 2 == 1).astype(np.uint8)  # GC_FGD = 1, GC_PR_FGD = 3
    return cv2.resize(obj, (w, h), interpolation=cv2.INTER_LINEAR if scale < 1 else cv2.INTER_NEAREST) > 0


def grabcut_mask(rgb: np.ndarray, margin: float = GRABCUT_MARGIN) -> np.ndarray:
    """(H, W) bool object pixels by GrabCut from the centred rectangle ``margin`` inside the image's edges,
    largest component kept."""
    return largest_component(grabcut_labels(rgb, None, margin))


def _disc(mask_shape: tuple[int, ...], band: float) -> np.ndarray:
    """A disc-shaped structuring element of radius ``band`` × the larger side of ``mask_shape`` (at least 2 px)."""
    r = max(2, round(band * max(mask_shape)))
    return np.hypot(*np.mgrid[-r : r + 1, -r : r + 1]) <= r


def thin_parts(mask: np.ndarray, radius: float) -> np.ndarray:
    """(H, W) bool: the pixels of the (H, W) bool ``mask`` where a disc of ``radius`` × the image's larger side (at
    least 2 px) does not fit inside it, its thin parts (a shaft, a bail, a blade's tip).

    Example:
        >>> m = np.zeros((100, 100), bool); m[20:60, 20:60] = True; m[38:42, 60:95] = True
        >>> bool(thin_parts(m, 0.03)[40, 80]), bool(thin_parts(m, 0.03)[40, 40])
        (True, False)
    """
    return mask & ~ndimage.binary_opening(mask, _disc(mask.shape, radius))


def trimap(mask: np.ndarray, band: float = TRIMAP_BAND) -> np.ndarray:
    """(H, W) uint8 GrabCut labels of an (H, W) bool mask: sure object inside, sure background outside, and unsure
    (probably as the mask says) in a band of ``band`` of the image's larger side around the mask's edge."""
    disc = _disc(mask.shape, band)
    inner = ndimage.binary_erosion(mask, disc)
    outer = ndimage.binary_dilation(mask, disc)
    labels = np.where(mask, 3, 2).astype(np.uint8)  # GC_PR_FGD, GC_PR_BGD
    labels[inner], labels[~outer] = 1, 0  # GC_FGD, GC_BGD
    return labels


def probability_trimap(
    prob: np.ndarray,
    mask: np.ndarray,
    band: float = PROBABILITY_TRIMAP_BAND,
    sure_background: float = PROBABILITY_SURE_BACKGROUND,
    sure_object: float | None = PROBABILITY_SURE_OBJECT,
    thin_radius: float | None = PROBABILITY_THIN_RADIUS,
) -> np.ndarray:
    """(H, W) uint8 GrabCut labels of an (H, W) bool mask that came from the (H, W) object probability ``prob``: as
    :func:`trimap` (with its own ``band``), except that outside the band only pixels below ``sure_background`` are
    sure background. The rest stay unsure, so GrabCut may add what the map half believes far from the mask (a thin
    part the threshold cut off), when its colours are the object's. The mask's thin parts (where a disc of radius
    ``thin_radius`` × the image's larger side does not fit; ``None``: the whole mask) are sure object where ``prob``
    is at least ``sure_object`` (``None``: nowhere), since the band leaves them no sure pixel.

    Example:
        >>> p = np.zeros((20, 20), np.float32); p[4:16, 4:16] = 0.95; p[0, 19] = 0.3; p[17, 2:18] = 0.9
        >>> labels = probability_trimap(p, p > 0.5, band=0.1)
        >>> int(labels[10, 10]), int(labels[5, 5]), int(labels[0, 0]), int(labels[0, 19]), int(labels[17, 10])
        (1, 3, 0, 2, 1)
        >>> int(probability_trimap(p, p > 0.5, band=0.1, sure_object=None)[17, 10])
        3
    """
    labels = trimap(mask, band)
    labels[(labels == 0) & (prob >= sure_background)] = 2  # GC_BGD -> GC_PR_BGD
    if sure_object is not None:
        thin = mask if thin_radius is None else thin_parts(mask, thin_radius)
        labels[thin & (prob >= sure_object)] = 1  # GC_FGD
    return labels


def refine_with_grabcut(
    rgb: np.ndarray, mask: np.ndarray, prob: np.ndarray | None = None, inside: np.ndarray | None = None
) -> np.ndarray:
    """The (H, W) bool mask's edges redrawn by GrabCut on the (H, W, 3) image, started from its trimap (from
    :func:`probability_trimap` when the (H, W) object probability ``prob`` the mask came from is given), every
    pixel outside ``inside`` ((H, W) bool, or everywhere) sure background; largest component kept."""
    labels = trimap(mask) if prob is None else probability_trimap(prob, mask)
    if inside is not None:
        labels[~inside] = 0  # GC_BGD
    return largest_component(grabcut_labels(rgb, labels))
