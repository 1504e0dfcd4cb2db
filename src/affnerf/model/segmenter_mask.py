"""From the object segmenter's probability map to the photo's object mask: hysteresis thresholds, the main region,
the sure fragments kept beside it, and how sure a mask is. Pure numpy functions of a map
(:mod:`affnerf.model.segmenter` makes the maps).
"""

from __future__ import annotations

import numpy as np

#: Probability above which a pixel is object.
SEGMENTER_THRESHOLD = 0.5
#: Probability above which a pixel is object when it is connected, through shared edges, to pixels above
#: :data:`SEGMENTER_THRESHOLD` (hysteresis, as Canny's edges: the faint middle of a thin shaft stays with its handle).
SEGMENTER_LOW_THRESHOLD = 0.4
#: The mask's main region is the one of largest size × (mean probability) ** this: a region the segmenter is less
#: sure of must be much larger to win (at 0.84 against 0.97, over three times the size), so the photo's own subject
#: (a cup, a person) no longer beats a smaller object the segmenter is sure of. Chosen on the composite benchmark's
#: seed-1 draws (8 to 32 level, 0 to 6 and "surest alone" worse), confirmed on seeds 0 and 2
#: (benchmarks/results/segmenter_u2netp.md, "Which region").
SEGMENTER_REGION_SURENESS_POWER = 8
#: ... among the regions of at least this share of the largest one's size (a sure speck is not the object; 0.1
#: kept every seed-1 gain, 0.25 lost a pen less than a quarter of the size of the cup beside it).
SEGMENTER_MAIN_MIN_SIZE = 0.1
#: Beside the main region of the mask, other regions are kept where the segmenter is this sure of them on
#: average (a screwdriver's tip cut off from its handle by a shaft it lost)...
SEGMENTER_EXTRA_CONFIDENCE = 0.9
#: ... at least this share of the main region's size...
SEGMENTER_EXTRA_SIZE = 0.01
#: ... and within this share of the photo's larger side of it (a thing further away is another thing).
SEGMENTER_EXTRA_DISTANCE = 0.1


def mask_confidence(prob: np.ndarray, mask: np.ndarray) -> float:
    """How sure the segmenter is of ``mask`` ((H, W) bool): the mean of its (H, W) probability ``prob`` over the
    mask, 0 when it is empty.

    Example:
        >>> p = np.array([[0.9, 0.7, 0.1]], np.float32)
        >>> round(mask_confidence(p, p > 0.5), 2), mask_confidence(p, p > 0.95)
        (0.8, 0.0)
    """
    return float(prob[mask].mean()) if mask.any() else 0.0


def hysteresis_mask(
    prob: np.ndarray, thresholds: tuple[float, float] = (SEGMENTER_LOW_THRESHOLD, SEGMENTER_THRESHOLD)
) -> np.ndarray:
    """(H, W) bool: pixels of ``prob`` above the high threshold, joined by touching ones above the low (hysteresis).

    >>> hysteresis_mask(np.array([[0.45, 0.6, 0.1, 0.45]])).astype(int).tolist()
    [[1, 1, 0, 0]]
    """
    from skimage.filters import apply_hysteresis_threshold

    return apply_hysteresis_threshold(np.asarray(prob, np.float32), *thresholds)


def probability_mask(
    prob: np.ndarray,
    inside: np.ndarray | None = None,
    power: float = SEGMENTER_REGION_SURENESS_POWER,
    main_min_size: float = SEGMENTER_MAIN_MIN_SIZE,
    thresholds: tuple[float, float] = (SEGMENTER_LOW_THRESHOLD, SEGMENTER_THRESHOLD),
) -> np.ndarray:
    """(H, W) bool object mask of the segmenter's (H, W) probability map: :func:`hysteresis_mask` at ``thresholds``;
    then, within ``inside`` ((H, W) bool, or everywhere), the main 8-connected region (the largest size × mean
    probability ** :data:`SEGMENTER_REGION_SURENESS_POWER` of those at least :data:`SEGMENTER_MAIN_MIN_SIZE` of the
    largest's size) and any other that the segmenter is on average :data:`SEGMENTER_EXTRA_CONFIDENCE` sure of, of at
    least :data:`SEGMENTER_EXTRA_SIZE` of the main one's size and within :data:`SEGMENTER_EXTRA_DISTANCE` of the
    photo's larger side of it. Chosen on the composite benchmark's seed-1 draws
    (benchmarks/results/segmenter_u2netp.md, "Hysteresis and fragments" and "Which region"); ``power`` and
    ``main_min_size`` replace the main region's two constants (benchmarks/segment_region_rule.py), ``thresholds``
    the hysteresis's (low, high) pair (benchmarks/segment_thresholds.py).

    Example:
        >>> p = np.zeros((3, 40)); p[1, :12] = 0.95; p[1, 12] = 0.45; p[1, 14] = 0.95; p[0, 0] = 0.45; p[1, 30] = 0.99
        >>> m = probability_mask(p)
        >>> m[1, 10:16].astype(int).tolist(), bool(m[0, 0]), bool(m[1, 30])
        ([1, 1, 1, 0, 1, 0], True, False)
    """
    from scipy import ndimage

    found = hysteresis_mask(prob, thresholds)
    if inside is not None:
        found &= inside
    labels, count = ndimage.label(found, structure=np.ones((3, 3)))
    if count <= 1:
        return found
    index = np.arange(1, count + 1)
    sizes, means = ndimage.sum(found, labels, index), ndimage.mean(prob, labels, index)
    score = np.where(sizes >= main_min_size * sizes.max(), sizes * means**power, -1)
    main = int(np.argmax(score))
    keep = (means >= SEGMENTER_EXTRA_CONFIDENCE) & (sizes >= SEGMENTER_EXTRA_SIZE * sizes[main])
    keep[main] = False
    if keep.any():
        gap = ndimage.minimum(ndimage.distance_transform_edt(labels != main + 1), labels, index)
        keep &= np.asarray(gap) <= SEGMENTER_EXTRA_DISTANCE * max(prob.shape)
    keep[main] = True
    return np.isin(labels, index[keep])
