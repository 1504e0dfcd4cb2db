"""Reading datasets: the index, each object's record, and its frames decoded lazily from the PNGs.

Nothing is decoded until asked for, so a dataset far larger than memory can be opened and sampled.

Use::

    ds = Dataset.open("data/mini")
    obj = ds.load_object(ds.objects(split="train")[0])
    obj.rgb(0).shape, obj.pose(0).shape                     # ((300, 400, 3), (4, 4)) for 400x300 frames
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from affnerf.data.format import DatasetIndex, IndexEntry, ObjectRecord, read_index, read_transforms
from affnerf.data.images import read_depth, read_labels, read_rgb
from affnerf.data.raycast import Frame
from affnerf.errors import input_error


@dataclass
class ObjectData:
    """One object folder: its ``transforms.json`` record and lazy access to its frames."""

    folder: Path
    record: ObjectRecord

    @classmethod
    def open(cls, folder: Path) -> ObjectData:
        """Read and validate ``folder/transforms.json``."""
        folder = Path(folder)
        return cls(folder, read_transforms(folder / "transforms.json"))

    def __len__(self) -> int:
        return len(self.record.frames)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of every frame."""
        return self.record.intrinsics.width, self.record.intrinsics.height

    @property
    def poses(self) -> np.ndarray:
        """(N, 4, 4) camera-to-world poses."""
        return np.stack([f.transform_matrix for f in self.record.frames])

    def pose(self, i: int) -> np.ndarray:
        """(4, 4) camera-to-world pose of frame ``i``."""
        return self.record.frames[i].transform_matrix

    def rgb(self, i: int) -> np.ndarray:
        """(H, W, 3) uint8 colour of frame ``i``."""
        return read_rgb(self.folder / self.record.frames[i].file_path, self.size)

    def depth(self, i: int) -> np.ndarray:
        """(H, W) float32 z-depth in metres of frame ``i`` (0 = no surface)."""
        unit = self.record.depth_unit_scale_factor
        return read_depth(self.folder / self.record.frames[i].depth_file_path, unit, self.size)

    def affordance(self, i: int) -> np.ndarray:
        """(H, W) uint8 affordance ids of frame ``i``."""
        path = self.folder / self.record.frames[i].affordance_file_path
        return read_labels(path, len(self.record.affordance_classes), self.size)

    def part(self, i: int) -> np.ndarray:
        """(H, W) uint8 part ids of frame ``i``."""
        path = self.folder / self.record.frames[i].part_file_path
        labels = read_labels(path, None, self.size)
        known = {0} | {p.id for p in self.record.parts}
        unknown = set(np.unique(labels).tolist()) - known
        if unknown:
            raise input_error(path, f"part ids {sorted(unknown)} are not in the object's parts")
        return labels

    def frame(self, i: int) -> Frame:
        """All four maps of frame ``i``."""
        return Frame(self.rgb(i), self.depth(i), self.affordance(i), self.part(i))


@dataclass
class Dataset:
    """A dataset root and its validated index."""

    root: Path
    index: DatasetIndex

    @classmethod
    def open(cls, root: Path | str) -> Dataset:
        """Read ``root/dataset.json``."""
        root = Path(root)
        return cls(root, read_index(root))

    @property
    def affordance_classes(self) -> list[str]:
        return self.index.affordance_classes

    @property
    def categories(self) -> list[str]:
        """The categories of the listed objects."""
        return sorted({o.category for o in self.index.objects})

    def objects(self, split: str | None = None, categories: list[str] | str | None = None) -> list[IndexEntry]:
        """Index entries, filtered by split and categories when given.

        Args:
            split: one split, or None for every split.
            categories: names, a comma-separated string of names (empty = all), or None for all.

        Raises:
            AffnerfError: naming ``dataset.json``, for a category the dataset does not have.
        """
        if isinstance(categories, str):
            categories = [c.strip() for c in categories.split(",") if c.strip()] or None
        if categories is not None:
            unknown = sorted(set(categories) - set(self.categories))
            if unknown:
                raise input_error(
                    self.root / "dataset.json",
                    f"unknown category {', '.join(unknown)} (this dataset has: {', '.join(self.categories)})",
                )
        return [
            o
            for o in self.index.objects
            if (split is None or o.split == split) and (categories is None or o.category in categories)
        ]

    def load_object(self, entry: IndexEntry | str) -> ObjectData:
        """Open one object by entry or id, checking it agrees with the index."""
        if isinstance(entry, str):
            matches = [o for o in self.index.objects if o.id == entry]
            if not matches:
                raise input_error(self.root / "dataset.json", f"no object with id {entry!r}")
            entry = matches[0]
        folder = self.root / entry.path
        if not (folder / "transforms.json").is_file():
            raise input_error(folder, "object folder listed in dataset.json is missing or incomplete")
        data = ObjectData.open(folder)
        if data.record.affordance_classes != self.affordance_classes:
            raise input_error(folder / "transforms.json", "affordance_classes differ from dataset.json")
        if data.record.category != entry.category:
            raise input_error(
                folder / "transforms.json", f"category {data.record.category!r}, dataset.json says {entry.category!r}"
            )
        return data


def interleave_categories(entries: list[IndexEntry], per_category: int = 0) -> list[IndexEntry]:
    """Entries taken round-robin over their categories (sorted by name), at most ``per_category`` of each (0: all),
    so that the first few span the categories (figures, contact sheets, capped evaluations)."""
    by_category: dict[str, list[IndexEntry]] = {}
    for entry in entries:
        group = by_category.setdefault(entry.category, [])
        if not per_category or len(group) < per_category:
            group.append(entry)
    queues = [by_category[name] for name in sorted(by_category)]
    ordered = []
    for rank in range(max((len(q) for q in queues), default=0)):
        ordered += [q[rank] for q in queues if rank < len(q)]
    return ordered
