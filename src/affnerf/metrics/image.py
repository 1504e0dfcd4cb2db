"""Image-quality metrics of rendered colour."""

from __future__ import annotations

import math

import numpy as np


def psnr(pred: np.ndarray, gt: np.ndarray) -> float:
    """Peak signal-to-noise ratio in dB of images in [0, 1] (inf for identical images)."""
    mse = float(np.mean((np.asarray(pred, np.float64) - np.asarray(gt, np.float64)) ** 2))
    return math.inf if mse == 0 else -10.0 * math.log10(mse)
