"""Generating a procedural dataset: which objects, their splits, shards, workers, resuming and progress.

Every object is a pure function of (seed, category, index): the same seed gives the same objects whichever shard
or worker makes them, so ``--shard I/N`` runs (or cluster array jobs) can fill one folder, and a rerun only makes
what is missing.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X, CameraSampler, Intrinsics
from affnerf.data.format import IndexEntry, read_index
from affnerf.data.index import update_index
from affnerf.data.pool import run_jobs
from affnerf.data.writer import clear_partial, is_complete, write_object
from affnerf.errors import AffnerfError
from affnerf.objects.registry import CATEGORY_NAMES, make_object, object_seed, parse_categories


@dataclass(frozen=True)
class GenerateConfig:
    """Settings of ``affnerf data generate``.

    Attributes:
        out: dataset folder, created or resumed.
        categories: categories to generate: ``all`` or a comma-separated list.
        objects_per_category: objects of each category (split 80/10/10 % train/val/test).
        views: views rendered per object.
        width: image width in pixels.
        height: image height in pixels.
        seed: seed of the whole dataset; objects, cameras and splits follow from it.
        workers: processes rendering objects in parallel.
        unseen: comma-separated categories kept out of training: all their objects go to split ``unseen``.
        shard: ``I/N`` makes the I-th (0-based) of N disjoint slices of the objects.
        camera_angle_x: horizontal field of view, radians.
        background: background colour, RGB in [0, 1] (multiples of 1/255 are kept exactly).
    """

    out: Path
    categories: str = "all"
    objects_per_category: int = 10
    views: int = 120
    width: int = 400
    height: int = 300
    seed: int = 0
    workers: int = 1
    unseen: str = ""
    shard: str = "0/1"
    camera_angle_x: float = DEFAULT_CAMERA_ANGLE_X
    background: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def settings(self) -> dict[str, Any]:
        """What decides the content of objects and splits, recorded in ``dataset.json``."""
        return {
            "seed": self.seed,
            "objects_per_category": self.objects_per_category,
            "views": self.views,
            "width": self.width,
            "height": self.height,
            "camera_angle_x": self.camera_angle_x,
            "background_color": list(self.background),
            "unseen": sorted(parse_categories(self.unseen)) if self.unseen.strip() else [],
        }


@dataclass(frozen=True)
class ObjectJob:
    """One object to make: its index entry and the seed it is built from."""

    entry: IndexEntry
    index: int


def parse_shard(text: str) -> tuple[int, int]:
    """Parse ``I/N`` (0 <= I < N).

    Example:
        >>> parse_shard("1/4")
        (1, 4)
    """
    try:
        i, n = (int(t) for t in text.split("/"))
    except ValueError:
        raise AffnerfError(f"--shard must be I/N with whole numbers, got {text!r}") from None
    if n < 1 or not 0 <= i < n:
        raise AffnerfError(f"--shard {text}: need 0 <= I < N")
    return i, n


def split_counts(n: int) -> tuple[int, int, int]:
    """Train, val and test counts for ``n`` instances: 80/10/10 %, with one val and one test from n = 3.

    Example:
        >>> split_counts(10), split_counts(5), split_counts(2)
        ((8, 1, 1), (3, 1, 1), (2, 0, 0))
    """
    if n < 3:
        return n, 0, 0
    val = max(1, round(0.1 * n))
    test = max(1, round(0.1 * n))
    return n - val - test, val, test


def instance_splits(seed: int, category: str, n: int) -> list[str]:
    """The split of each of ``n`` instances of a trained category, a seeded shuffle of the 80/10/10 counts."""
    train, val, test = split_counts(n)
    labels = np.array(["train"] * train + ["val"] * val + ["test"] * test)
    rng = np.random.default_rng([int(seed), CATEGORY_NAMES.index(category), 7])
    return labels[rng.permutation(n)].tolist()


def plan_jobs(config: GenerateConfig) -> list[ObjectJob]:
    """All objects of the dataset in a fixed order, with ids, folders and splits."""
    unseen = set(parse_categories(config.unseen)) if config.unseen.strip() else set()
    jobs = []
    for category in parse_categories(config.categories):
        n = config.objects_per_category
        splits = ["unseen"] * n if category in unseen else instance_splits(config.seed, category, n)
        for i in range(n):
            oid = f"{category}_{i:04d}"
            jobs.append(ObjectJob(IndexEntry(oid, category, f"{category}/{oid}", splits[i], "procedural"), i))
    return jobs


def camera_poses(seed: int, category: str, index: int, views: int) -> np.ndarray:
    """(views, 4, 4) camera-to-world poses of one object, from its own random stream."""
    rng = np.random.default_rng(object_seed(seed, category, index).spawn(2)[1])
    return CameraSampler().sample(rng, views)


def make_job_object(config: GenerateConfig, job: ObjectJob, on_frame: Any = None) -> Path:
    """Build, render and write one object."""
    seq = object_seed(config.seed, job.entry.category, job.index).spawn(2)[0]
    asset = make_object(job.entry.category, seq)
    intr = Intrinsics.from_fov(config.width, config.height, config.camera_angle_x)
    poses = camera_poses(config.seed, job.entry.category, job.index, config.views)
    return write_object(config.out, job.entry, asset, poses, intr, config.background, {"seed": config.seed}, on_frame)


def make_job_entry(config: GenerateConfig, job: ObjectJob, on_frame: Any = None) -> IndexEntry:
    """Make one object (as :func:`make_job_object`) and return its index entry: the work of a pool worker."""
    make_job_object(config, job, on_frame)
    return job.entry


def _check_settings(config: GenerateConfig) -> dict[str, Any]:
    """Refuse to resume into a folder generated with other settings (the objects would not match).

    Returns:
        The generation settings recorded in the folder's ``dataset.json`` (empty if none).
    """
    path = Path(config.out) / "dataset.json"
    if not path.is_file():
        return {}
    previous = read_index(config.out).extra.get("generation")
    if previous is None:
        return {}
    current = config.settings()
    for key, value in current.items():
        if key in previous and previous[key] != value:
            raise AffnerfError(
                f"{path}: generated with {key}={previous[key]!r}, not {value!r}; use another --out or the same settings"
            )
    return previous


@dataclass
class GenerateReport:
    """What a run did: objects made, objects found complete, frames rendered, seconds taken."""

    made: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    frames: int = 0
    seconds: float = 0.0

    @property
    def frames_per_second(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else math.nan


def generate_dataset(config: GenerateConfig, progress: bool = True) -> GenerateReport:
    """Generate (or resume) this shard's objects of the dataset and list them in ``dataset.json``.

    An object is listed only once its folder is complete; objects found complete are skipped.
    """
    if config.objects_per_category < 1 or config.views < 1 or config.width < 1 or config.height < 1:
        raise AffnerfError("objects per category, views, width and height must be positive")
    if config.workers < 1:
        raise AffnerfError("--workers must be at least 1")
    shard_i, shard_n = parse_shard(config.shard)
    mine = plan_jobs(config)[shard_i::shard_n]  # validates the settings before anything is written
    previous = _check_settings(config)
    categories = set(parse_categories(config.categories)) | set(previous.get("categories", []))
    settings = ("generation", {**config.settings(), "categories": [c for c in CATEGORY_NAMES if c in categories]})
    root = Path(config.out)
    root.mkdir(parents=True, exist_ok=True)
    done = [j for j in mine if is_complete(root / j.entry.path)]
    todo = [j for j in mine if not is_complete(root / j.entry.path)]
    report = GenerateReport(skipped=[j.entry.id for j in done])
    update_index(root, [j.entry for j in done], settings)
    for job in todo:
        clear_partial(root, job.entry.id)
    start = time.perf_counter()
    bars = _Bars(len(todo), len(todo) * config.views, progress)
    try:
        if config.workers == 1 or len(todo) <= 1:
            for job in todo:
                make_job_object(config, job, on_frame=bars.frame)
                update_index(root, [job.entry])
                report.made.append(job.entry.id)
                bars.object()
        else:
            for entry in run_jobs(partial(make_job_entry, config), todo, config.workers, bars.frames.update):
                update_index(root, [entry])
                report.made.append(entry.id)
                bars.object()
    finally:
        bars.close()
    report.seconds = time.perf_counter() - start
    report.frames = len(report.made) * config.views
    return report


class _Bars:
    """Two progress bars, objects and frames."""

    def __init__(self, objects: int, frames: int, enabled: bool) -> None:
        self.objects = tqdm(total=objects, desc="objects", unit="obj", position=0, disable=not enabled)
        self.frames = tqdm(total=frames, desc="frames ", unit="frame", position=1, disable=not enabled)

    def frame(self) -> None:
        self.frames.update(1)

    def object(self) -> None:
        self.objects.update(1)

    def close(self) -> None:
        self.frames.close()
        self.objects.close()
