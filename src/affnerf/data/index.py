"""Maintaining ``dataset.json``: merging new objects in under a lock, and rebuilding it from the object folders.

Several processes (shards, cluster array jobs, an import beside a generation) may fill one dataset folder; each
update takes an exclusive lock on ``<root>/.dataset.lock``, reads the current index, merges and writes it
atomically, so no update is lost and the file is never half-written.
"""

from __future__ import annotations

import fcntl
import logging
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from affnerf.data.format import (
    FORMAT,
    SPLITS,
    DatasetIndex,
    IndexEntry,
    parse_index,
    read_transforms,
)
from affnerf.data.writer import PARTIAL_DIR, is_complete
from affnerf.errors import input_error
from affnerf.fileio import read_json_file, write_json_atomic
from affnerf.vocab import AFFORDANCE_CLASSES

log = logging.getLogger(__name__)


@contextmanager
def index_lock(root: Path) -> Iterator[None]:
    """Hold an exclusive lock on the dataset's index while the block runs."""
    Path(root).mkdir(parents=True, exist_ok=True)
    with open(Path(root) / ".dataset.lock", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _load_or_new(root: Path) -> DatasetIndex:
    path = Path(root) / "dataset.json"
    if path.is_file():
        return parse_index(read_json_file(path), path)
    return DatasetIndex(list(AFFORDANCE_CLASSES), [], {})


def _sorted(entries: Iterable[IndexEntry]) -> list[IndexEntry]:
    return sorted(entries, key=lambda e: (e.category, e.id))


def update_index(
    root: Path,
    entries: Iterable[IndexEntry],
    settings: tuple[str, dict[str, Any]] | None = None,
) -> DatasetIndex:
    """Add (or replace, by id) objects in ``root/dataset.json``, creating it if needed.

    Args:
        root: dataset root.
        entries: complete objects to list.
        settings: optional ``(key, value)`` stored at the top level (e.g. the generation settings).

    Returns:
        The index as written.
    """
    with index_lock(root):
        index = _load_or_new(root)
        merged = {e.id: e for e in index.objects}
        merged.update({e.id: e for e in entries})
        index.objects = _sorted(merged.values())
        if settings is not None:
            index.extra[settings[0]] = settings[1]
        write_json_atomic(Path(root) / "dataset.json", index.to_json())
    return index


def scan_objects(root: Path) -> list[IndexEntry]:
    """Index entries of every complete object folder under ``root`` (temporary folders are ignored)."""
    root = Path(root)
    entries = []
    for transforms in sorted(root.rglob("transforms.json")):
        folder = transforms.parent
        if PARTIAL_DIR in folder.relative_to(root).parts or not is_complete(folder):
            continue
        record = read_transforms(transforms)
        split = record.extra.get("split", "train")
        if split not in SPLITS:
            raise input_error(transforms, f"split {split!r} is not one of {SPLITS}")
        if "split" not in record.extra:
            log.warning("%s: no 'split' recorded; listed as train", transforms)
        source = str(record.extra.get("source", "procedural"))
        entries.append(
            IndexEntry(record.object_id, record.category, folder.relative_to(root).as_posix(), split, source)
        )
    ids = [e.id for e in entries]
    duplicates = sorted({i for i in ids if ids.count(i) > 1})
    if duplicates:
        raise input_error(root, f"object ids used by more than one folder: {', '.join(duplicates)}")
    return entries


def rebuild_index(root: Path) -> DatasetIndex:
    """Rewrite ``root/dataset.json`` from the complete object folders, keeping its other keys."""
    root = Path(root)
    if not root.is_dir():
        raise input_error(root, "dataset folder not found")
    with index_lock(root):
        path = root / "dataset.json"
        extra = {}
        if path.is_file():
            try:
                extra = parse_index(read_json_file(path), path).extra
            except Exception as exc:  # a damaged index is what a rebuild is for
                log.warning("%s: unreadable (%s); rebuilt from the object folders", path, exc)
        index = DatasetIndex(list(AFFORDANCE_CLASSES), _sorted(scan_objects(root)), extra)
        write_json_atomic(path, index.to_json())
    return index


__all__ = ["FORMAT", "index_lock", "rebuild_index", "scan_objects", "update_index"]
