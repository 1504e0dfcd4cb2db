"""Per-step schedules of a run: the learning rate, the weight of the 3D supervision and the share of fine samples
drawn around the true surface.

All are pure functions of the resolved config and the step (steps done so far, 0-based), so a resumed run and a
fresh one take the same values at the same step.
"""

from __future__ import annotations

import math

from affnerf.train.config import TrainConfig


def _progress(step: int, start: int, end: int) -> float:
    """Fraction of the span from step ``start`` to step ``end`` done at ``step``: 0 at ``start`` and before, 1 at
    ``end`` and after."""
    return min(max((step - start) / max(end - start, 1), 0.0), 1.0)


def cosine_fall(high: float, low: float, frac: float) -> float:
    """Half a cosine from ``high`` at ``frac`` 0 to ``low`` at ``frac`` 1 (the training and segmenter schedules).

    Example:
        >>> cosine_fall(1.0, 0.0, 0.0), cosine_fall(1.0, 0.0, 0.5), cosine_fall(1.0, 0.0, 1.0)
        (1.0, 0.5, 0.0)
    """
    return low + (high - low) * 0.5 * (1.0 + math.cos(math.pi * frac))


def learning_rate(config: TrainConfig, step: int) -> float:
    """The rate of ``step``: a linear rise to ``optim.lr`` over ``optim.warmup_steps`` steps (at most a tenth of
    ``steps``; 0 = none), then a fall to ``optim.lr_final`` at the last step, exponential or half a cosine
    (``optim.schedule``); constant after.

    Example:
        >>> from pathlib import Path
        >>> c = TrainConfig(data=Path("."), out=Path("."), steps=100)
        >>> learning_rate(c, 0), round(learning_rate(c, 50), 12), round(learning_rate(c, 100), 12)
        (0.0005, 0.000158113883, 5e-05)
        >>> learning_rate(c, 250) == learning_rate(c, 100)
        True
    """
    optim = config.optim
    warm = min(optim.warmup_steps, config.steps // 10)
    if step < warm:
        return optim.lr * (step + 1) / warm
    frac = _progress(step, warm, config.steps)
    if optim.schedule == "cosine":
        return cosine_fall(optim.lr, optim.lr_final, frac)
    return optim.lr * (optim.lr_final / optim.lr) ** frac


def points_weight(config: TrainConfig, step: int) -> float:
    """The 3D supervision's weight μ at ``step``: ``points_weight`` throughout, or, with ``points_weight_final``
    >= 0, a straight line from ``points_weight`` at step 0 to ``points_weight_final`` at the last step.

    Example:
        >>> from pathlib import Path
        >>> c = TrainConfig(data=Path("."), out=Path("."), steps=100, points_weight=1.0, points_weight_final=0.1)
        >>> [round(points_weight(c, s), 6) for s in (0, 50, 100, 150)]
        [1.0, 0.55, 0.1, 0.1]
        >>> points_weight(TrainConfig(data=Path("."), out=Path("."), points_weight=0.3), 7)
        0.3
    """
    if config.points_weight_final < 0:
        return config.points_weight
    frac = _progress(step, 0, config.steps)
    return (1.0 - frac) * config.points_weight + frac * config.points_weight_final


def surface_sample_share(config: TrainConfig, step: int) -> float:
    """The share of each surface ray's fine samples drawn around its true depth at ``step``: a straight line from
    ``surface_sample_share`` at step 0 to 0 at ``surface_sample_until`` of ``steps``, 0 after.

    Example:
        >>> from pathlib import Path
        >>> c = TrainConfig(data=Path("."), out=Path("."), steps=100, surface_sample_share=0.5)
        >>> [surface_sample_share(c, s) for s in (0, 25, 50, 80)]
        [0.5, 0.25, 0.0, 0.0]
    """
    if config.surface_sample_share <= 0:
        return 0.0
    frac = _progress(step, 0, round(config.surface_sample_until * config.steps))
    return config.surface_sample_share * (1.0 - frac)
