"""Adding PartNet-Mobility objects to a dataset (new or existing): load, map parts, render, list."""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from tqdm import tqdm

from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X, CameraSampler, Intrinsics
from affnerf.data.format import SPLITS, IndexEntry
from affnerf.data.index import update_index
from affnerf.data.writer import write_object
from affnerf.errors import AffnerfError


@dataclass(frozen=True)
class ImportConfig:
    """Settings of ``affnerf data import-partnet``.

    Attributes:
        out: dataset folder (created if needed; other objects in it are kept).
        views: views rendered per object.
        width: image width in pixels.
        height: image height in pixels.
        split: split the imported objects are listed under.
        mapping: YAML file overriding the shipped part-name -> affordance table.
        strict: fail on a part the mapping does not name, instead of giving it the category's default.
        joint_state: ``rest`` (as modelled, clamped to the joint limits) or ``random`` (uniform in the limits).
        seed: seed of the cameras and random joint states.
        camera_angle_x: horizontal field of view, radians.
        background: background colour, RGB in [0, 1].
    """

    out: Path
    views: int = 120
    width: int = 400
    height: int = 300
    split: str = "test"
    mapping: Path | None = None
    strict: bool = False
    joint_state: Literal["rest", "random"] = "rest"
    seed: int = 0
    camera_angle_x: float = DEFAULT_CAMERA_ANGLE_X
    background: tuple[float, float, float] = (1.0, 1.0, 1.0)


def _object_rng(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def import_partnet(sources: Sequence[Path], config: ImportConfig, progress: bool = True) -> list[IndexEntry]:
    """Import PartNet-Mobility object folders into ``config.out``.

    Object ids are ``<category>_pm<folder name>`` (plus ``_s<seed>`` for random joint states), so importing the
    same object again replaces it rather than duplicating it.

    Returns:
        The index entries written.
    """
    from affnerf.data.partnet import load_partnet_object

    if config.split not in SPLITS:
        raise AffnerfError(f"--split must be one of {', '.join(SPLITS)}, got {config.split!r}")
    if config.views < 1:
        raise AffnerfError("--views must be at least 1")
    # load everything first: a bad source fails the command before anything is written
    assets = []
    for src in sources:
        rng = _object_rng(config.seed, Path(src).name)
        asset = load_partnet_object(Path(src), config.joint_state, rng, config.mapping, config.strict)
        assets.append((Path(src), asset, rng))
    intr = Intrinsics.from_fov(config.width, config.height, config.camera_angle_x)
    entries = []
    bar = tqdm(total=len(assets) * config.views, desc="frames", unit="frame", disable=not progress)
    try:
        for src, asset, rng in assets:
            suffix = f"_s{config.seed}" if config.joint_state == "random" else ""
            oid = f"{asset.category}_pm{src.name}{suffix}"
            entry = IndexEntry(oid, asset.category, f"{asset.category}/{oid}", config.split, "partnet-mobility")
            poses = CameraSampler().sample(rng, config.views)
            extra = {"partnet_source": str(src.resolve())}
            write_object(config.out, entry, asset, poses, intr, config.background, extra, on_frame=lambda: bar.update(1))
            update_index(config.out, [entry])
            entries.append(entry)
    finally:
        bar.close()
    return entries
