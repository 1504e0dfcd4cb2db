"""Whether a photo's object is overexposed: of the global lighting and camera changes measured
(``benchmarks/results/photo_conditions.md``), clipped highlights are the one that costs the shipped model much.

A channel at or above :data:`CLIPPED_LEVEL` has lost what the object's colour was there. The procedural renders the
model learnt from never clip (no object pixel of 192 test views does). An exposure of 1.4× clips at least one channel
of over :data:`OVEREXPOSED_SHARE` of the object's pixels in 5 of those 16 benchmark photos, and 4 of the 5 lost
0.28-0.39 mIoU. The other 11 were level with their clean photos on average (+0.001).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["CLIPPED_LEVEL", "OVEREXPOSED_SHARE", "clipped_share", "overexposure_warning"]

#: An 8-bit channel value at or above which a pixel's colour counts as clipped.
CLIPPED_LEVEL = 250
#: Share of the object's pixels with a clipped channel above which the photo counts as overexposed.
OVEREXPOSED_SHARE = 0.25


def clipped_share(rgb: np.ndarray, mask: np.ndarray) -> float:
    """Share of the object's pixels with at least one channel at or above :data:`CLIPPED_LEVEL`.

    Args:
        rgb: (H, W, 3) uint8 photo.
        mask: (H, W) bool object pixels.

    Returns:
        A share in [0, 1]; 0 for an empty mask.

    Example:
        >>> rgb = np.zeros((2, 2, 3), np.uint8); rgb[0, 0] = (255, 120, 40); rgb[1, 1] = (250, 250, 250)
        >>> clipped_share(rgb, np.array([[True, True], [False, True]]))
        0.6666666666666666
    """
    pixels = rgb[mask]
    if len(pixels) == 0:
        return 0.0
    return float((pixels >= CLIPPED_LEVEL).any(axis=-1).mean())


def overexposure_warning(image: Path, share: float) -> str | None:
    """The one-line warning of an overexposed object (``None`` when at most :data:`OVEREXPOSED_SHARE` clips)."""
    if share <= OVEREXPOSED_SHARE:
        return None
    return (
        f"{image}: the photo is overexposed ({share:.0%} of the object's pixels have a colour channel at its maximum), "
        f"and the model's labels may be wrong (on test objects photographed 1.4 times too bright, the overexposed ones "
        f"lost 0.3 mIoU); a photo with less exposure, or without direct light on the object, is better"
    )
