"""View stability (conventions §5): how much a method's scores of one object move with the input view.

Every object is predicted from N input-view sets, the same for every method: the protocol's own inputs first, then
the frames that follow its targets in the same seeded order (so the targets stay the same and never overlap any
input). Per object the **spread** of a metric is its maximum minus its minimum over the N sets; spreads are
averaged per category and over categories like the other metrics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

#: The metrics whose spread is reported.
STABILITY_KEYS = ("mIoU", "fscore_1cm")


def input_sets(order: list[int], input_views: int, target_views: int, count: int) -> list[list[int]]:
    """``count`` sorted input-view sets from a seeded frame order whose first ``input_views`` frames are the
    inputs and next ``target_views`` the targets: the inputs, then consecutive groups after the targets.

    Raises:
        ValueError: when the order is too short for ``count`` sets.

    Example:
        >>> input_sets([5, 2, 7, 0, 3, 1, 4, 6], 1, 3, 3)  # inputs [5], targets 2 7 0
        [[5], [3], [1]]
    """
    needed = input_views * count + target_views
    if len(order) < needed:
        raise ValueError(f"{count} input-view sets need {needed} frames, there are {len(order)}")
    rest = order[input_views + target_views :]
    others = [rest[i * input_views : (i + 1) * input_views] for i in range(count - 1)]
    return [sorted(s) for s in [order[:input_views], *others]]


def spread(values: list[float | None]) -> float | None:
    """Maximum minus minimum; None when any value is missing or not finite.

    Example:
        >>> spread([0.5, 0.75, 0.25]), spread([0.5, None])
        (0.5, None)
    """
    finite = [float(v) for v in values if v is not None and math.isfinite(v)]
    if not finite or len(finite) < len(values):
        return None
    return max(finite) - min(finite)


@dataclass
class StabilityRecord:
    """One object's scores from each input-view set (``fscore_1cm`` entries None without a mesh)."""

    object_id: str
    category: str
    inputs: list[list[int]]
    mIoU: list[float]
    fscore_1cm: list[float | None]

    def to_json(self) -> dict[str, Any]:
        """The scores, and the spread of each metric."""
        return {
            "category": self.category,
            "inputs": self.inputs,
            "mIoU": self.mIoU,
            "fscore_1cm": self.fscore_1cm,
            "mIoU_spread": spread(list(self.mIoU)),
            "fscore_1cm_spread": spread(self.fscore_1cm),
        }


def _mean(values: list[float | None]) -> float | None:
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.mean(finite)) if finite else None


def stability_json(records: list[StabilityRecord], views: int) -> dict[str, Any]:
    """``{"views", "objects": {id: scores and spreads}, "categories": {name: mean spreads, "objects"}, "mean"}``;
    ``mean`` averages the category means where finite."""
    objects = {r.object_id: r.to_json() for r in records}
    categories: dict[str, dict[str, Any]] = {}
    for name in sorted({r.category for r in records}):
        mine = [o for o in objects.values() if o["category"] == name]
        categories[name] = {f"{k}_spread": _mean([o[f"{k}_spread"] for o in mine]) for k in STABILITY_KEYS}
        categories[name]["objects"] = len(mine)
    mean: dict[str, Any] = {
        f"{k}_spread": _mean([c[f"{k}_spread"] for c in categories.values()]) for k in STABILITY_KEYS
    }
    mean["objects"] = len(records)
    return {"views": views, "objects": objects, "categories": categories, "mean": mean}


def records_from_json(section: dict[str, Any]) -> list[StabilityRecord]:
    """The per-object records of a :func:`stability_json` section (its spreads are recomputed from them)."""
    return [
        StabilityRecord(oid, o["category"], o["inputs"], o["mIoU"], o["fscore_1cm"])
        for oid, o in section["objects"].items()
    ]


def merge_stability(sections: list[dict[str, Any]]) -> dict[str, Any]:
    """One :func:`stability_json` section from sections of disjoint objects (evaluations run side by side), as one
    evaluation of all of them gives.

    Raises:
        ValueError: when the sections used different numbers of input-view sets or share an object.
    """
    if len({s["views"] for s in sections}) != 1:
        raise ValueError("merge_stability: the parts used different numbers of input-view sets")
    records = [r for s in sections for r in records_from_json(s)]
    if len({r.object_id for r in records}) < len(records):
        raise ValueError("merge_stability: an object is in more than one part")
    return stability_json(records, sections[0]["views"])
