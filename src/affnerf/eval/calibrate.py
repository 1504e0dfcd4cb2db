"""``affnerf eval calibrate``: choose the density level of a model's meshes (``ModelConfig.surface_density``) from
the 3D metrics on a split (conventions §5), and store it with the model.

For up to ``max_objects`` objects of the split (round-robin over categories), the object is encoded from the
protocol's seeded input view(s) (as in Table 2), the fine field's density is evaluated once on a grid (in the
object's occupied cells, as :meth:`~affnerf.eval.methods.affnerf.ConditionedNeRFMethod.mesh` does), and marching
cubes at each candidate level gives a labelled mesh scored against the object's true mesh: F-score at 1 cm,
Chamfer-L1 and 3D affordance mIoU (an empty mesh scores F = 0). The levels are ranked by mean F-score (ties: the
higher 3D mIoU, then the level closest to the current one). A second sweep, at each of the ``depth_levels`` best
levels, tries each candidate ``surface_optical_depth`` (:mod:`affnerf.predict.level`: the level lowered per object
for diffuse objects; 0 = off) on the same grids, and the (level, optical depth) pair with the highest mean F-score
wins (ties: the higher 3D mIoU, the level closest to the current one, the smaller depth). Sweeping the depths at
one level only let two near-equal levels decide the result: a lower level where no depth helps beat, by 0.002 F at
depth 0, a higher one that a per-object level raises by 0.05 (benchmarks/results/points_schedule.md). The sweeps are
written to ``calibration.json`` and, unless ``dry_run``, both values replace ``surface_density`` and
``surface_optical_depth`` in the model config stored in the checkpoint (fields that may change in a checkpoint:
``model.config.NON_ARCHITECTURE_FIELDS``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from affnerf.data.dataset import Dataset, ObjectData, interleave_categories
from affnerf.errors import AffnerfError, input_error
from affnerf.eval.calibration_choice import (
    best_levels,
    choose_level_and_depth,
    summarise_levels,
    summarise_optical_depths,
)
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.eval.surface import SurfaceScore, sample_seed, score_mesh, true_samples
from affnerf.fileio import atomic_write, write_json_atomic
from affnerf.metrics.surface import SurfaceSamples
from affnerf.predict.level import object_level
from affnerf.predict.loading import LoadedModel, load_model, resolve_checkpoint
from affnerf.predict.mesh import PointFn, evaluate_grid, labelled_mesh_from_grid
from affnerf.predict.predictor import pick_device
from affnerf.train.checkpoint import load_checkpoint

#: Candidate surface densities (per metre) of the sweep.
DEFAULT_LEVELS = (5.0, 10.0, 20.0, 35.0, 50.0, 75.0, 100.0, 150.0, 200.0)
#: Candidate optical depths of the per-object level (:mod:`affnerf.predict.level`); 0 switches it off.
DEFAULT_OPTICAL_DEPTHS = (0.0, 1.5, 2.0, 3.0, 4.0, 6.0)
CALIBRATION_NAME = "calibration.json"


@dataclass(frozen=True)
class CalibrateConfig:
    """Settings of ``affnerf eval calibrate``.

    Attributes:
        data: the dataset (its objects' true meshes score the levels).
        run: a trained run folder (its newest checkpoint is calibrated) or a checkpoint file.
        checkpoint: a single checkpoint file instead of ``run`` (e.g. the shipped ``affnerf-small.pt``).
        split: the split whose objects score the levels.
        categories: only these categories (comma-separated; empty = all), e.g. a leave-one-category-out run's
            training categories, so the held-out category never chooses its level.
        levels: candidate surface densities (per metre).
        optical_depths: candidate ``surface_optical_depth`` values of the second sweep (0 = per-object levels off).
        depth_levels: how many of the best levels the second sweep tries the optical depths at.
        max_objects: at most this many objects, taken round-robin over the split's categories.
        resolution: marching-cubes samples per axis.
        input_views: views each object is encoded from, chosen by the protocol's seed (as in Table 2).
        seed: seed of the view choice and of the surface samples.
        dry_run: write ``calibration.json`` only; leave the checkpoint as it is.
        device: ``auto``, ``cpu`` or ``cuda``.
        out: where to write ``calibration.json`` (None: RUN/calibration.json, or beside a checkpoint file as
            ``<name>.calibration.json``).
    """

    data: Path
    run: Path | None = None
    checkpoint: Path | None = None
    split: str = "val"
    categories: str = ""
    levels: tuple[float, ...] = DEFAULT_LEVELS
    optical_depths: tuple[float, ...] = DEFAULT_OPTICAL_DEPTHS
    depth_levels: int = 2
    max_objects: int = 16
    resolution: int = 96
    input_views: int = 1
    seed: int = 0
    dry_run: bool = False
    device: str = "auto"
    out: Path | None = None


def model_source(config: CalibrateConfig) -> Path:
    """The run folder or checkpoint file to calibrate (exactly one of ``run`` and ``checkpoint``).

    Raises:
        AffnerfError: when neither or both are given, or the checkpoint is not a file.
    """
    if (config.run is None) == (config.checkpoint is None):
        raise AffnerfError("give exactly one of --run (a run folder) and --checkpoint (a checkpoint file)")
    if config.checkpoint is not None and not Path(config.checkpoint).is_file():
        raise input_error(config.checkpoint, "checkpoint not found")
    return Path(config.run if config.run is not None else config.checkpoint)  # type: ignore[arg-type]


def calibration_path(source: Path, out: Path | None = None) -> Path:
    """Where the sweep is written: ``out``, else ``RUN/calibration.json``, else ``<checkpoint>.calibration.json``.

    Example:
        >>> calibration_path(Path("weights/affnerf-small.pt")).name
        'affnerf-small.calibration.json'
    """
    if out is not None:
        return Path(out)
    source = Path(source)
    if source.is_dir():
        return source / CALIBRATION_NAME
    return source.with_suffix(f".{CALIBRATION_NAME}")


def calibration_objects(ds: Dataset, split: str, max_objects: int, categories: str = "") -> list[ObjectData]:
    """The first ``max_objects`` objects of ``split`` (of ``categories`` only, when given) taken round-robin over
    its categories.

    Raises:
        AffnerfError: naming ``dataset.json``, when the split has no objects (of those categories).
    """
    entries = interleave_categories(ds.objects(split, categories or None))[: max(max_objects, 0)]
    if not entries:
        wanted = f" of categories {categories}" if categories else ""
        raise input_error(ds.root / "dataset.json", f"no objects in split {split!r}{wanted} to calibrate on")
    return [ds.load_object(e) for e in entries]


def input_views(obj: ObjectData, count: int, seed: int) -> list[int]:
    """The protocol's seeded input views of ``obj`` (:func:`affnerf.eval.protocol.choose_views`, as in Table 2)."""
    return choose_views(len(obj), obj.record.object_id, ProtocolConfig(input_views=count, target_views=0, seed=seed))[0]


def object_grid(method: ConditionedNeRFMethod, obj: ObjectData, inputs: list[int]) -> tuple[np.ndarray, PointFn]:
    """The fine field's density of ``obj`` encoded from ``inputs``, on a (R, R, R) grid of the model's scene cube
    (evaluated in the encoding's occupied cells only), and its (N, 3) -> (N,) label function."""
    model = method.loaded.model
    encoding, grid = method.encoded(obj, inputs), method.occupancy(obj, inputs)
    density, labels = model.point_fields(encoding)
    volume = evaluate_grid(density, method.mesh_resolution, model.config.scene_half_extent, occupancy=grid)
    return volume, labels


@torch.no_grad()
def sweep_grid(
    volume: np.ndarray,
    labels: PointFn,
    levels: tuple[float, ...],
    half_extent: float,
    truth: SurfaceSamples,
    seed: list[int],
) -> list[SurfaceScore]:
    """One object's 3D scores (``SURFACE_KEYS``) of the mesh at each level of an evaluated (R, R, R) grid."""
    scores = []
    for level in levels:
        mesh = labelled_mesh_from_grid(volume, labels, level, half_extent)
        scores.append(score_mesh(mesh, truth, seed))
    return scores  # type: ignore[return-value]


@dataclass(frozen=True)
class ObjectGrid:
    """One calibration object: its (R, R, R) density grid, label function, true surface samples and sample seed."""

    volume: np.ndarray
    labels: PointFn
    truth: SurfaceSamples
    seed: list[int]


@torch.no_grad()
def sweep_optical_depths(
    grid: ObjectGrid,
    depths: tuple[float, ...],
    level: float,
    half_extent: float,
    scored: dict[float, SurfaceScore] | None = None,
) -> list[SurfaceScore]:
    """One object's 3D scores with each candidate ``surface_optical_depth`` at base level ``level`` (each score
    also gives the object's ``level``); depths that give the same level share one mesh, and ``scored`` (level ->
    score, e.g. the level sweep's score at ``level``) saves meshing those levels again."""
    spacing = 2.0 * half_extent / (grid.volume.shape[0] - 1)
    scored = dict(scored or {})
    scores = []
    for depth in depths:
        own = object_level(grid.volume, spacing, level, depth)
        if own not in scored:
            mesh = labelled_mesh_from_grid(grid.volume, grid.labels, own, half_extent)
            scored[own] = score_mesh(mesh, grid.truth, grid.seed)  # type: ignore[assignment]
        scores.append({**scored[own], "level": own})
    return scores


def store_surface(path: Path, level: float, optical_depth: float) -> None:
    """Set ``surface_density`` and ``surface_optical_depth`` of the model config stored in the checkpoint at
    ``path``, in place and atomically (temporary file + rename); every other entry is kept."""
    data = load_checkpoint(path)
    if not isinstance(data.get("model_config"), dict):
        raise input_error(path, "checkpoint has no model config")
    surface = {"surface_density": float(level), "surface_optical_depth": float(optical_depth)}
    data["model_config"] = {**data["model_config"], **surface}
    atomic_write(Path(path), lambda f: torch.save(data, f))


def check_config(config: CalibrateConfig) -> None:
    """Refuse settings that cannot give a sweep (no levels, a level ≤ 0, too coarse a grid, no objects)."""
    if not config.levels or any(not (math.isfinite(v) and v > 0) for v in config.levels):
        raise AffnerfError(f"--levels must be positive densities per metre, got {list(config.levels)}")
    if not config.optical_depths or any(not (math.isfinite(v) and v >= 0) for v in config.optical_depths):
        raise AffnerfError(f"--optical-depths must be non-negative (0 = off), got {list(config.optical_depths)}")
    if config.resolution < 2 or min(config.max_objects, config.input_views, config.depth_levels) < 1:
        raise AffnerfError(
            "--resolution must be at least 2, --max-objects, --input-views and --depth-levels at least 1"
        )


def _load(source: Path, ds: Dataset, device: str) -> LoadedModel:
    """The model to calibrate, checked to have the dataset's affordance classes."""
    loaded = load_model(source, pick_device(device))
    if loaded.classes != ds.affordance_classes:
        raise input_error(loaded.path, f"trained with other affordance classes than {ds.root / 'dataset.json'}")
    return loaded


def calibration_grids(
    method: ConditionedNeRFMethod, objects: list[ObjectData], config: CalibrateConfig
) -> tuple[list[ObjectGrid], dict[str, list[int]]]:
    """Each object's grid (encoded from the protocol's seeded input views) and those views, by object id."""
    grids, views = [], {}
    for obj in objects:
        inputs = input_views(obj, config.input_views, config.seed)
        volume, labels = object_grid(method, obj, inputs)
        seed = sample_seed(config.seed, obj.record.object_id)
        grids.append(ObjectGrid(volume, labels, true_samples(obj, config.seed), seed))
        views[obj.record.object_id] = inputs
    return grids, views


def depth_sweeps(
    grids: list[ObjectGrid],
    level_scores: list[list[SurfaceScore]],
    levels: tuple[float, ...],
    at: list[float],
    depths: tuple[float, ...],
    half_extent: float,
) -> dict[float, list[dict[str, Any]]]:
    """The optical-depth sweep's rows (:func:`summarise_optical_depths`) at each level in ``at``, by level; each
    object's score at the base level is taken from its level sweep (``level_scores[i][levels.index(level)]``)."""
    by_level = {}
    for level in at:
        j = levels.index(level)
        scores = [
            sweep_optical_depths(g, depths, level, half_extent, {level: s[j]})
            for g, s in zip(grids, level_scores, strict=True)
        ]
        by_level[level] = summarise_optical_depths(depths, scores)
    return by_level


def run_calibration(config: CalibrateConfig) -> dict[str, Any]:
    """Sweep the levels, then the optical depths at the best levels, write ``calibration.json`` and (unless
    ``dry_run``) store the chosen pair in the checkpoint; returns what was written."""
    check_config(config)
    source = model_source(config)
    resolve_checkpoint(source)  # a missing run fails before the dataset is read
    ds = Dataset.open(config.data)
    loaded = _load(source, ds, config.device)
    objects = calibration_objects(ds, config.split, config.max_objects, config.categories)
    method = ConditionedNeRFMethod(loaded, mesh_resolution=config.resolution)
    half_extent = loaded.model.config.scene_half_extent
    grids, views = calibration_grids(method, objects, config)
    levels, depths = tuple(config.levels), tuple(config.optical_depths)
    previous = float(loaded.model.config.surface_density)
    level_scores = [sweep_grid(g.volume, g.labels, levels, half_extent, g.truth, g.seed) for g in grids]
    rows = summarise_levels(levels, level_scores)
    at = best_levels(rows, previous, config.depth_levels)
    by_level = depth_sweeps(grids, level_scores, levels, at, depths, half_extent)
    chosen, chosen_depth = choose_level_and_depth(by_level, previous)
    result = {
        "checkpoint": str(loaded.path),
        "split": config.split,
        "resolution": config.resolution,
        "levels": rows,
        "optical_depths": by_level[chosen],
        "optical_depths_by_level": [{"level": level, "optical_depths": r} for level, r in by_level.items()],
        "objects": views,
        "previous_level": previous,
        "chosen_level": chosen,
        "previous_optical_depth": float(loaded.model.config.surface_optical_depth),
        "chosen_optical_depth": chosen_depth,
        "stored": not config.dry_run,
    }
    write_json_atomic(calibration_path(source, config.out), result)
    if not config.dry_run:
        store_surface(loaded.path, chosen, chosen_depth)
    return result


def sweep_lines(result: dict[str, Any]) -> list[str]:
    """What ``affnerf eval calibrate`` prints: one line per level, one per optical depth at each level it was swept
    at, then the chosen pair."""
    lines = []
    for row in result["levels"]:
        chamfer = "-" if row["chamfer_l1"] is None else f"{row['chamfer_l1']:.4f}"
        lines.append(
            f"level {row['level']:g}/m: F@1cm {row['fscore_1cm']:.3f}  Chamfer {chamfer}  "
            f"3D mIoU {row['affordance_miou_3d']:.3f}  (empty {row['meshes_empty']}/{len(result['objects'])})"
        )
    for sweep in result["optical_depths_by_level"]:
        for row in sweep["optical_depths"]:
            lines.append(
                f"at {sweep['level']:g}/m, optical depth {row['optical_depth']:g}: F@1cm {row['fscore_1cm']:.3f}  "
                f"3D mIoU {row['affordance_miou_3d']:.3f}  (mean level {row['mean_level']:.1f}/m)"
            )
    where = f"stored in {result['checkpoint']}" if result["stored"] else "dry run: checkpoint unchanged"
    lines.append(
        f"chosen level {result['chosen_level']:g}/m (was {result['previous_level']:g}/m), optical depth "
        f"{result['chosen_optical_depth']:g} (was {result['previous_optical_depth']:g}; {where})"
    )
    return lines
