"""A run's training objects, cached once beside the run (or in ``cache_dir``): their frames, decoded and
memory-mapped, and their 3D supervision points. Under ``torchrun`` every rank makes its share of the objects
first (:func:`made_by_ranks`), then all ranks open every object from the cache.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from tqdm import tqdm

from affnerf.data.dataset import Dataset
from affnerf.data.format import IndexEntry
from affnerf.errors import AffnerfError
from affnerf.train import distributed as dist_utils
from affnerf.train.cache import ObjectFrames, cached_frames, cached_points
from affnerf.train.config import TrainConfig
from affnerf.train.points import PointSet

__all__ = ["cache_dir", "load_frames", "load_points", "made_by_ranks"]

T = TypeVar("T")


def cache_dir(config: TrainConfig) -> Path:
    """Where the run's frames and points are cached: ``cache_dir``, or ``OUT/cache``."""
    return Path(config.cache_dir) if config.cache_dir else Path(config.out) / "cache"


def made_by_ranks(
    entries: list[IndexEntry], make: Callable[[IndexEntry], T], desc: str, config: TrainConfig, ctx: dist_utils.Context
) -> list[T]:
    """``make`` of every entry: each rank first makes its share (every ``world``-th entry from its rank, a progress
    bar on the main rank), all wait for each other, then every entry is made again, now a read of the cache."""
    show = config.progress and ctx.is_main
    for entry in tqdm(entries[ctx.rank :: ctx.world], desc=desc, unit="obj", disable=not show):
        make(entry)
    dist_utils.barrier(ctx)
    return [make(entry) for entry in entries]


def load_frames(config: TrainConfig, ds: Dataset, ctx: dist_utils.Context) -> list[ObjectFrames]:
    """Decode (once) and memory-map the training objects' frames."""
    entries = ds.objects("train", config.categories)
    if not entries:
        wanted = config.categories or "all"
        raise AffnerfError(f"{ds.root / 'dataset.json'}: no training objects (split train, categories {wanted})")
    cache, crop = cache_dir(config), config.model.encoder_resolution

    def frames(entry: IndexEntry) -> ObjectFrames:
        return cached_frames(ds.load_object(entry), cache, config.image_scale, crop)

    return made_by_ranks(entries, frames, "caching frames", config, ctx)


def load_points(config: TrainConfig, ds: Dataset, ctx: dist_utils.Context) -> dict[str, PointSet]:
    """Make (once) and memory-map the training objects' 3D supervision points, by object id."""
    entries = ds.objects("train", config.categories)
    sigmas = (config.point_sigma_near, config.point_sigma_far)  # checked by check_options

    def points(entry: IndexEntry) -> PointSet:
        return cached_points(
            ds.root / entry.path / "mesh.ply",
            entry.id,
            cache_dir(config),
            config.model.scene_half_extent,
            sigmas,
            part_balance=config.point_part_balance,
            uniform_share=config.point_uniform_share,
        )

    made = made_by_ranks(entries, points, "caching points", config, ctx)
    return {entry.id: p for entry, p in zip(entries, made, strict=True)}
