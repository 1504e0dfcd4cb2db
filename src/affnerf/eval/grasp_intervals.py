"""How sure Table 3's comparisons are: the difference between each restricted row and the whole surface of the same
mesh (share of grasps on the true task part, lift and lift-and-disturb success), with a percentile bootstrap
interval over objects.

A table of five objects per category and five lifted grasps each moves by one or two grasps when other objects
are drawn, so "restricted at least as good as unrestricted" needs its uncertainty beside it. The objects, not the
grasps, are what is drawn again: each category's objects are resampled with replacement (as many as it has, so
every category keeps its weight in the mean), the whole summary (:func:`~affnerf.eval.grasp_table.summarise`, with
its rule that a mesh's rows average over the same categories) is computed on the draw, and the difference is taken
there. Both rows of a draw use the same objects, so the interval is that of a paired comparison.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from affnerf.eval.grasp_table import CONDITIONS, summarise, whole_of

#: The rows compared with the whole surface of their mesh.
RESTRICTED = tuple(c for c in CONDITIONS if not c.endswith("_whole"))
#: The metrics whose differences get an interval (ε has its ratio column instead).
COMPARED = ("on_part_share", "lift_success", "disturb_success")
DRAWS = 2000  #: bootstrap draws
LEVEL = 0.95  #: the interval's coverage


def restriction_differences(summary: dict[str, Any]) -> dict[str, dict[str, float | None]]:
    """``{restricted condition: {metric: its mean minus the whole surface's of the same mesh}}`` from a
    :func:`summarise` result (None where either mean is undefined)."""
    out: dict[str, dict[str, float | None]] = {}
    for cond in RESTRICTED:
        mean, whole = summary["mean"][cond], summary["mean"][whole_of(cond)]
        out[cond] = {
            key: None if mean[key] is None or whole[key] is None else float(mean[key] - whole[key]) for key in COMPARED
        }
    return out


def resample_within_categories(objects: list[dict[str, Any]], rng: np.random.Generator) -> list[dict[str, Any]]:
    """One bootstrap draw: each category's objects drawn with replacement, as many as the category has (N → N)."""
    draw: list[dict[str, Any]] = []
    for category in sorted({o["category"] for o in objects}):
        rows = [o for o in objects if o["category"] == category]
        draw += [rows[i] for i in rng.integers(len(rows), size=len(rows))]
    return draw


def restriction_intervals(
    objects: list[dict[str, Any]], draws: int = DRAWS, level: float = LEVEL, seed: int = 0
) -> dict[str, Any]:
    """The differences of :func:`restriction_differences` on ``objects`` with their ``level`` percentile bootstrap
    intervals over ``draws`` draws of :func:`resample_within_categories`: ``{"draws", "level", "rows": {cond:
    {metric: {"difference", "low", "high", "draws"}}}}`` (``draws`` per cell: those where the difference was
    defined; low and high None when none was)."""
    rng = np.random.default_rng(seed)
    point = restriction_differences(summarise(objects))
    samples: dict[tuple[str, str], list[float]] = {(c, k): [] for c in RESTRICTED for k in COMPARED}
    for _ in range(draws):
        for cond, diffs in restriction_differences(summarise(resample_within_categories(objects, rng))).items():
            for key, value in diffs.items():
                if value is not None:
                    samples[(cond, key)].append(value)
    tail = 100 * (1 - level) / 2
    rows: dict[str, dict[str, Any]] = {c: {} for c in RESTRICTED}
    for (cond, key), values in samples.items():
        low, high = np.percentile(values, [tail, 100 - tail]) if values else (None, None)
        rows[cond][key] = {
            "difference": point[cond][key],
            "low": None if low is None else float(low),
            "high": None if high is None else float(high),
            "draws": len(values),
        }
    return {"draws": draws, "level": level, "rows": rows}


def table3_summary(objects: list[dict[str, Any]]) -> dict[str, Any]:
    """Table 3's summary (:func:`summarise`) with the restricted rows' intervals under ``"intervals"`` (which
    :func:`~affnerf.eval.grasp_table.table3_markdown` shows)."""
    return {**summarise(objects), "intervals": restriction_intervals(objects)}
