"""The calibration sweep's tables and the choice made from them (conventions §5): per level and per optical depth,
the 3D metrics averaged over the calibration objects, and the ranking that picks the (level, optical depth) pair.
Pure functions of the per-object scores; :mod:`affnerf.eval.calibrate` makes the scores and stores the choice.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from affnerf.eval.surface import SurfaceScore
from affnerf.metrics.surface import SURFACE_KEYS


def summarise_optical_depths(depths: tuple[float, ...], scores: list[list[SurfaceScore]]) -> list[dict[str, Any]]:
    """Per candidate optical depth, the 3D metrics averaged over objects (as :func:`summarise_levels`) and the
    mean of the objects' levels. ``scores[i][j]``: object i at depth j."""
    rows = []
    for j, row in enumerate(summarise_levels(tuple(depths), scores)):
        mean_level = float(np.mean([s[j]["level"] for s in scores]))
        rows.append({"optical_depth": row.pop("level"), **row, "mean_level": mean_level})
    return rows


def _mean(values: list[float | None]) -> float | None:
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.mean(finite)) if finite else None


def summarise_levels(levels: tuple[float, ...], scores: list[list[SurfaceScore]]) -> list[dict[str, Any]]:
    """Per level, the 3D metrics averaged over objects (Chamfer over the non-empty meshes; None when all are
    empty) and the number of empty meshes. ``scores[i][j]``: object i at level j.

    Example:
        >>> rows = summarise_levels((10.0, 50.0), [[{"chamfer_l1": 0.01, "fscore_1cm": 0.6,
        ...     "affordance_miou_3d": 0.5}, {"chamfer_l1": None, "fscore_1cm": 0.0, "affordance_miou_3d": 0.0}]])
        >>> [(r["level"], r["fscore_1cm"], r["meshes_empty"]) for r in rows]
        [(10.0, 0.6, 0), (50.0, 0.0, 1)]
    """
    rows = []
    for j, level in enumerate(levels):
        at_level = [s[j] for s in scores]
        row: dict[str, Any] = {"level": float(level)}
        for key in SURFACE_KEYS:
            values = [s[key] for s in at_level]
            row[key] = _mean(values) if key == "chamfer_l1" else float(np.mean([v or 0.0 for v in values]))
        row["meshes_empty"] = sum(s["chamfer_l1"] is None for s in at_level)
        rows.append(row)
    return rows


def _level_key(row: dict[str, Any], previous: float) -> tuple[float, float, float]:
    """Sort key of a level's row: mean F-score, then 3D mIoU, then closeness to ``previous`` (higher is better)."""
    return round(row["fscore_1cm"], 9), round(row["affordance_miou_3d"], 9), -abs(row["level"] - previous)


def choose_level(rows: list[dict[str, Any]], previous: float) -> float:
    """The level with the highest mean F-score; ties: the higher 3D mIoU, then the level closest to ``previous``.

    Example:
        >>> rows = [{"level": 20.0, "fscore_1cm": 0.5, "affordance_miou_3d": 0.3},
        ...         {"level": 75.0, "fscore_1cm": 0.5, "affordance_miou_3d": 0.3},
        ...         {"level": 200.0, "fscore_1cm": 0.1, "affordance_miou_3d": 0.9}]
        >>> choose_level(rows, 50.0)
        75.0
    """
    return best_levels(rows, previous, 1)[0]


def best_levels(rows: list[dict[str, Any]], previous: float, count: int) -> list[float]:
    """The ``count`` best levels of the sweep, best first (ranked as :func:`choose_level`).

    Example:
        >>> rows = [{"level": 20.0, "fscore_1cm": 0.667, "affordance_miou_3d": 0.65},
        ...         {"level": 35.0, "fscore_1cm": 0.665, "affordance_miou_3d": 0.59},
        ...         {"level": 50.0, "fscore_1cm": 0.62, "affordance_miou_3d": 0.52}]
        >>> best_levels(rows, 50.0, 2)
        [20.0, 35.0]
    """
    ranked = sorted(rows, key=lambda r: _level_key(r, previous), reverse=True)
    return [float(r["level"]) for r in ranked[:count]]


def choose_level_and_depth(by_level: dict[float, list[dict[str, Any]]], previous: float) -> tuple[float, float]:
    """The (level, optical depth) pair with the highest mean F-score over the depth sweeps at each level in
    ``by_level``; ties: the higher 3D mIoU, the level closest to ``previous``, then the smaller depth.

    Example:
        >>> by_level = {20.0: [{"optical_depth": 0.0, "fscore_1cm": 0.667, "affordance_miou_3d": 0.65}],
        ...             35.0: [{"optical_depth": 0.0, "fscore_1cm": 0.665, "affordance_miou_3d": 0.59},
        ...                    {"optical_depth": 4.0, "fscore_1cm": 0.717, "affordance_miou_3d": 0.62}]}
        >>> choose_level_and_depth(by_level, 50.0)
        (35.0, 4.0)
    """
    pairs = [(level, row) for level, rows in by_level.items() for row in rows]
    level, row = max(pairs, key=lambda p: (*_level_key({**p[1], "level": p[0]}, previous), -p[1]["optical_depth"]))
    return float(level), float(row["optical_depth"])
