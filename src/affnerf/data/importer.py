"""Adding PartNet-Mobility objects to a dataset (new or existing): load, map parts, render, list."""

from __future__ import annotations

import hashlib
import logging
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from tqdm import tqdm

from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X, CameraSampler, Intrinsics
from affnerf.data.format import SPLITS, IndexEntry
from affnerf.data.index import update_index
from affnerf.data.writer import is_complete, write_object
from affnerf.errors import AffnerfError, input_error
from affnerf.fileio import read_json_file
from affnerf.objects.asset import ObjectAsset

logger = logging.getLogger(__name__)


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
        overwrite: replace objects already in ``out`` that were imported with other settings (each swapped in
            once its new folder is complete); without it such a re-import is refused before anything is written.
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
    overwrite: bool = False

    def settings(self) -> dict[str, Any]:
        """What decides an imported object's folder, as recorded in (or read back from) its ``transforms.json``."""
        mapping = None if self.mapping is None else hashlib.sha256(Path(self.mapping).read_bytes()).hexdigest()[:16]
        return {
            "views": self.views,
            "width": self.width,
            "height": self.height,
            "camera_angle_x": self.camera_angle_x,
            "background": list(self.background),
            "joint_state": self.joint_state,
            "split": self.split,
            "seed": self.seed,
            "mapping_sha256": mapping,
        }


def recorded_settings(transforms: dict[str, Any]) -> dict[str, Any]:
    """The import settings of an object folder, from the parsed ``transforms.json``.

    The camera, frame count, joint state and split are read from the record itself, so folders imported before
    ``import_settings`` was recorded are compared on those; ``seed`` and ``mapping_sha256`` come from
    ``import_settings`` when present.
    """
    return {
        "views": len(transforms.get("frames", [])),
        "width": transforms.get("w"),
        "height": transforms.get("h"),
        "camera_angle_x": transforms.get("camera_angle_x"),
        "background": transforms.get("background_color"),
        "joint_state": transforms.get("params", {}).get("joint_state"),
        "split": transforms.get("split"),
        **transforms.get("import_settings", {}),
    }


def settings_difference(previous: dict[str, Any], current: dict[str, Any]) -> tuple[str, Any, Any] | None:
    """The first setting recorded in both with different values, as ``(key, previous, current)``; ``None`` if none.

    Example:
        >>> settings_difference({"views": 4, "width": 64}, {"views": 8, "width": 64, "seed": 1})
        ('views', 4, 8)
    """
    for key, value in current.items():
        if key in previous and previous[key] != value:
            return key, previous[key], value
    return None


def existing_copy_action(folder: Path, settings: dict[str, Any], overwrite: bool) -> str:
    """What to do about an object folder already in the dataset: ``write`` (none there), ``keep`` (same settings)
    or ``replace`` (other settings, with ``overwrite``).

    Raises:
        AffnerfError: naming its ``transforms.json``, when it was imported with other settings and ``overwrite``
            is not set (nothing is written).
    """
    if not is_complete(folder):
        return "write"
    if overwrite:
        return "replace"
    difference = settings_difference(recorded_settings(read_json_file(folder / "transforms.json")), settings)
    if difference is None:
        return "keep"
    key, old, new = difference
    raise input_error(
        folder / "transforms.json",
        f"already imported with {key}={old!r}, not {new!r}; import with the same settings, pass --overwrite to "
        f"replace it, or use another --out",
    )


def _object_rng(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def import_partnet(sources: Sequence[Path], config: ImportConfig, progress: bool = True) -> list[IndexEntry]:
    """Import PartNet-Mobility object folders into ``config.out``.

    Object ids are ``<category>_pm<folder name>`` (plus ``_s<seed>`` for random joint states), so the same object
    is never listed twice. An object already imported with the same settings is kept (not rendered again); one
    imported with other settings is refused, or replaced with ``config.overwrite`` (see
    :func:`existing_copy_action`). Every source is loaded and every existing copy checked before anything is
    written, so a refused or failed import leaves the dataset as it was.

    Returns:
        The index entries of the imported objects (kept ones included).
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
    settings = config.settings()
    entries = [object_entry(src, asset, config) for src, asset, _ in assets]
    actions = [existing_copy_action(Path(config.out) / e.path, settings, config.overwrite) for e in entries]
    intr = Intrinsics.from_fov(config.width, config.height, config.camera_angle_x)
    recorded = {"import_settings": {"seed": settings["seed"], "mapping_sha256": settings["mapping_sha256"]}}
    todo = sum(action != "keep" for action in actions)
    bar = tqdm(total=todo * config.views, desc="frames", unit="frame", disable=not progress)
    try:
        for (src, asset, rng), entry, action in zip(assets, entries, actions, strict=True):
            if action == "keep":
                logger.info("%s: already imported with the same settings; kept", Path(config.out) / entry.path)
            else:
                poses = CameraSampler().sample(rng, config.views)
                extra = {"partnet_source": str(src.resolve()), **recorded}
                write_object(
                    config.out,
                    entry,
                    asset,
                    poses,
                    intr,
                    config.background,
                    extra,
                    on_frame=lambda: bar.update(1),
                    replace=action == "replace",
                )
            update_index(config.out, [entry])
    finally:
        bar.close()
    return entries


def object_entry(src: Path, asset: ObjectAsset, config: ImportConfig) -> IndexEntry:
    """The index entry of an imported object: id ``<category>_pm<folder name>[_s<seed>]``, folder
    ``<category>/<id>``."""
    suffix = f"_s{config.seed}" if config.joint_state == "random" else ""
    oid = f"{asset.category}_pm{src.name}{suffix}"
    return IndexEntry(oid, asset.category, f"{asset.category}/{oid}", config.split, "partnet-mobility")
