"""Random appearance for procedural parts: colours and solid-texture materials drawn from a generator."""

from __future__ import annotations

import colorsys
from collections.abc import Sequence

import numpy as np

from affnerf.objects.asset import Material

Color = tuple[float, float, float]


def random_color(
    rng: np.random.Generator,
    hue: tuple[float, float] = (0.0, 1.0),
    saturation: tuple[float, float] = (0.35, 0.9),
    value: tuple[float, float] = (0.35, 0.95),
) -> Color:
    """An RGB colour in [0, 1] drawn uniformly in HSV within the given ranges."""
    h = rng.uniform(*hue) % 1.0
    rgb = colorsys.hsv_to_rgb(h, rng.uniform(*saturation), rng.uniform(*value))
    return (float(rgb[0]), float(rgb[1]), float(rgb[2]))


def shade(color: Color, factor: float) -> Color:
    """``color`` scaled by ``factor`` and clipped to [0, 1] (darker below 1, lighter above)."""
    return tuple(float(np.clip(c * factor, 0.0, 1.0)) for c in color)  # type: ignore[return-value]


def metal(rng: np.random.Generator) -> Material:
    """A plain steel-like grey with a slight random tint."""
    v = rng.uniform(0.55, 0.8)
    tint = rng.uniform(-0.03, 0.03, size=3)
    return Material(color=tuple(float(np.clip(v + t, 0, 1)) for t in tint))  # type: ignore[arg-type]


def random_material(
    rng: np.random.Generator,
    palette: Sequence[Color] | None = None,
    pattern_probability: float = 0.25,
    period: tuple[float, float] = (0.006, 0.03),
) -> Material:
    """A material with a random colour (from ``palette`` when given) and, sometimes, a procedural pattern.

    Args:
        rng: the random generator.
        palette: colours to choose from; ``None`` draws any saturated colour.
        pattern_probability: chance of stripes, checker or speckle instead of a plain colour.
        period: range of the pattern period in metres.
    """
    base = palette[rng.integers(len(palette))] if palette else random_color(rng)
    if rng.uniform() >= pattern_probability:
        return Material(color=base)
    pattern = ("stripes", "checker", "speckle")[rng.integers(3)]
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    return Material(
        color=base,
        pattern=pattern,
        color2=shade(base, rng.uniform(0.45, 0.75)),
        period=float(rng.uniform(*period)),
        axis=(float(axis[0]), float(axis[1]), float(axis[2])),
    )
