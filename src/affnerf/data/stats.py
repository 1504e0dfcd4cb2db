"""Dataset statistics: objects per category and split, and the share of pixels of each affordance."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from affnerf.data.dataset import Dataset
from affnerf.data.format import SPLITS


@dataclass
class DatasetStats:
    """Counts of a dataset.

    Attributes:
        classes: affordance class names.
        objects: (category, split) -> number of objects.
        pixels: (C,) pixel count per affordance class over the sampled frames.
        frames: number of frames counted.
    """

    classes: list[str]
    objects: Counter = field(default_factory=Counter)
    pixels: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    frames: int = 0

    def pixel_share(self, object_only: bool = False) -> np.ndarray:
        """(C,) fraction of pixels per class; with ``object_only`` over non-background pixels (background 0)."""
        counts = self.pixels.astype(np.float64).copy()
        if object_only:
            counts[0] = 0.0
        total = counts.sum()
        return counts / total if total > 0 else counts

    def to_json(self) -> dict:
        """A JSON-ready summary."""
        return {
            "objects": {f"{c}/{s}": n for (c, s), n in sorted(self.objects.items())},
            "frames_counted": self.frames,
            "pixel_share": dict(zip(self.classes, self.pixel_share().round(6).tolist(), strict=True)),
            "pixel_share_object": dict(zip(self.classes, self.pixel_share(True).round(6).tolist(), strict=True)),
        }

    def table(self) -> str:
        """The statistics as two plain-text tables."""
        cats = sorted({c for c, _ in self.objects})
        lines = [f"{'category':<14}" + "".join(f"{s:>8}" for s in SPLITS) + f"{'total':>8}"]
        for c in cats:
            row = [self.objects.get((c, s), 0) for s in SPLITS]
            lines.append(f"{c:<14}" + "".join(f"{n:>8}" for n in row) + f"{sum(row):>8}")
        totals = [sum(self.objects.get((c, s), 0) for c in cats) for s in SPLITS]
        lines.append(f"{'all':<14}" + "".join(f"{n:>8}" for n in totals) + f"{sum(totals):>8}")
        lines += ["", f"pixel share over {self.frames} frames:", f"{'affordance':<14}{'all px':>10}{'object px':>11}"]
        share, share_obj = self.pixel_share(), self.pixel_share(True)
        for i, name in enumerate(self.classes):
            if self.pixels[i] > 0:
                obj = "" if i == 0 else f"{100 * share_obj[i]:>10.2f}%"
                lines.append(f"{name:<14}{100 * share[i]:>9.2f}%{obj}")
        return "\n".join(lines)


def dataset_stats(root: Path, views_per_object: int = 8) -> DatasetStats:
    """Count objects per category and split, and affordance pixels over evenly spaced frames of each object.

    Args:
        root: dataset root.
        views_per_object: frames read per object for the pixel shares (0 reads every frame).
    """
    ds = Dataset.open(root)
    stats = DatasetStats(classes=ds.affordance_classes, pixels=np.zeros(len(ds.affordance_classes), np.int64))
    for entry in ds.objects():
        stats.objects[(entry.category, entry.split)] += 1
        obj = ds.load_object(entry)
        n = len(obj)
        chosen = (
            range(n)
            if views_per_object <= 0 or views_per_object >= n
            else np.linspace(0, n - 1, views_per_object).round().astype(int)
        )
        for i in chosen:
            stats.pixels += np.bincount(obj.affordance(int(i)).reshape(-1), minlength=len(stats.classes))
            stats.frames += 1
    return stats
