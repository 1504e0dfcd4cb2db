"""``affnerf eval``: run the Table 2 protocol for one or more methods and write metrics, table and figure.

Each method's results go to ``OUT/metrics_<method>.json`` (conventions §5 schema); ``OUT/metrics.json`` holds
AFF-NeRF's once it has been evaluated into ``OUT``, and until then the first method's. ``OUT/table2.md`` and
``OUT/figure.png`` are rebuilt from every method evaluated into ``OUT`` so far, so methods evaluated in separate
calls end up in one table. One call can also evaluate every method: ``--method`` gives each its input views
(``pixelnerf-3v``) and ``--runs`` each its own trained run.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

from PIL import Image

import affnerf.eval.methods  # noqa: F401  (registers the built-in methods)
from affnerf.data.dataset import Dataset, ObjectData, interleave_categories
from affnerf.errors import AffnerfError
from affnerf.eval.protocol import Method, ProtocolConfig, evaluate
from affnerf.eval.registry import MethodContext, method_spec, parse_method_views
from affnerf.eval.report import figure_grid, read_method_results, save_examples, table2_markdown
from affnerf.fileio import write_json_atomic
from affnerf.model.config import RAYS_PER_CHUNK


@dataclass(frozen=True)
class EvalConfig:
    """Settings of ``affnerf eval``.

    Attributes:
        run: the trained run (AFF-NeRF for ``affnerf`` and ``retrieval``; a run of the method's own kind for
            ``pixelnerf``, ``semantic-ray`` and ``gsnerf``; not used by ``semantic-nerf`` and ``constant``).
        data: the dataset.
        out: output folder.
        split: ``test`` (held-out instances), ``unseen`` (held-out categories), ``val``, or ``all`` (every object,
            e.g. of a category a leave-one-category-out run never saw).
        method: one or more registered methods, comma-separated (built in: affnerf, affnerf-fit (AFF-NeRF with
            test-time inversion), pixelnerf, semantic-ray, gsnerf, semantic-nerf, retrieval, constant; ``all`` =
            every method but affnerf-fit and constant); see :mod:`affnerf.eval.registry`. A ``-<N>v`` suffix gives
            that method N input views instead of ``--input-views`` (``affnerf,retrieval,pixelnerf-3v``; its
            results are filed under that label).
        runs: trained runs of single methods, ``name=PATH`` comma-separated (``pixelnerf=runs/pix,gsnerf=runs/gs``):
            each named method loads its run from here instead of ``--run``, so one call evaluates every method.
        input_views: views each method is given (1: single image; PixelNeRF-M, Semantic-Ray and GSNeRF are also
            run with 3 posed views, Semantic-NeRF with 20 as a many-view reference).
        target_views: views scored per object (K = 20 in conventions §5).
        scale: resolution of scored views as a fraction of the dataset's images.
        seed: seed of the view choice.
        categories: only these categories (comma-separated; empty = all).
        max_objects: at most this many objects per category (0 = all).
        semantic_steps: optimisation steps of each per-object Semantic-NeRF.
        device: ``auto``, ``cpu`` or ``cuda``.
        chunk: rays per forward pass.
        figure_objects: example objects in the figure (one per category, up to this many).
        fast: render every method with its objects' occupancy grids (empty-space skipping).
        metrics_3d: also score each method's labelled mesh against the object's true ``mesh.ply`` (Chamfer-L1,
            F-score at 1 cm, 3D affordance mIoU; conventions §5); ``--no-metrics-3d`` gives the 2D-only run.
        mesh_resolution: marching-cubes samples per axis of the meshes AFF-NeRF, PixelNeRF-M and Semantic-NeRF
            extract for the 3D metrics.
        stability_views: predict every object from this many input-view sets (the same for every method) and
            report the spread (max - min) of its mIoU and F-score; 0 = off, else at least 2.
    """

    run: Path
    data: Path
    out: Path
    split: Literal["test", "unseen", "val", "all"] = "test"
    method: str = "affnerf"
    runs: str = ""
    input_views: int = 1
    target_views: int = 20
    scale: float = 1.0
    seed: int = 0
    categories: str = ""
    max_objects: int = 0
    semantic_steps: int = 400
    device: str = "auto"
    chunk: int = RAYS_PER_CHUNK
    figure_objects: int = 8
    fast: bool = True
    metrics_3d: bool = True
    mesh_resolution: int = 128
    stability_views: int = 0


def _objects(ds: Dataset, config: EvalConfig, input_views: int) -> list[ObjectData]:
    """The evaluated objects, each checked to have views enough for the most ``input_views`` a method gets."""
    entries = ds.objects(None if config.split == "all" else config.split, config.categories)
    if not entries:
        raise AffnerfError(f"{ds.root / 'dataset.json'}: no objects in split {config.split!r}")
    objects = [ds.load_object(e) for e in interleave_categories(entries, config.max_objects)]
    needed = input_views * max(config.stability_views, 1) + config.target_views
    short = [o.record.object_id for o in objects if len(o) < needed]
    if short:
        raise AffnerfError(
            f"{short[0]} has fewer than {needed} views (input views × max(stability views, 1) + target views)"
        )
    return objects


def parse_runs(text: str) -> dict[str, Path]:
    """Per-method runs from ``name=PATH,...`` (``--runs``).

    Raises:
        AffnerfError: for an entry without ``=``, an unknown method, a method named twice, or a path that does not
            exist.
    """
    runs: dict[str, Path] = {}
    for entry in (e.strip() for e in text.split(",") if e.strip()):
        name, sep, path = (part.strip() for part in entry.partition("="))
        if not sep or not name or not path:
            raise AffnerfError(f"--runs {entry!r}: expected name=PATH (e.g. pixelnerf=runs/pix)")
        try:
            name = method_spec(name).name
        except AffnerfError as err:
            raise AffnerfError(f"--runs {entry!r}: {err}") from None
        if name in runs:
            raise AffnerfError(f"--runs names {name} twice")
        if not Path(path).exists():
            raise AffnerfError(f"--runs {entry!r}: {path}: no such file or folder")
        runs[name] = Path(path)
    return runs


def method_requests(config: EvalConfig) -> list[tuple[str, int]]:
    """The methods to evaluate with the input views each is given (``--method``, ``--input-views``).

    Raises:
        AffnerfError: for an unknown method, or two entries filed under one label (``pixelnerf-3v`` beside
            ``pixelnerf`` with ``--input-views 3``).
    """
    requests = [(name, views or config.input_views) for name, views in parse_method_views(config.method)]
    labels = [method_label(name, views) for name, views in requests]
    twice = next((label for i, label in enumerate(labels) if label in labels[:i]), None)
    if twice is not None:
        raise AffnerfError(f"--method {config.method!r} evaluates {twice} twice")
    if not requests:
        raise AffnerfError("--method names no method")
    return requests


def build_method(name: str, config: EvalConfig, ds: Dataset, run: Path | None = None) -> Method:
    """The method registered under ``name``, built for this evaluation (loading ``run``, by default ``--run``)."""
    context = MethodContext(
        ds,
        Path(config.run if run is None else run),
        config.device,
        config.chunk,
        config.fast,
        config.semantic_steps,
        config.mesh_resolution,
    )
    return method_spec(name).build(context)


def method_label(name: str, input_views: int) -> str:
    """The name a method's results are filed under: with its input views when not 1 (``pixelnerf-3v``)."""
    return name if input_views == 1 else f"{name}-{input_views}v"


def protocol_config(config: EvalConfig, input_views: int | None = None) -> ProtocolConfig:
    """The protocol settings of an evaluation, for a method given ``input_views`` (default: ``--input-views``).

    Raises:
        AffnerfError: for ``--stability-views`` 1 or negative, or a ``--mesh-resolution`` below 2 with 3D metrics.
    """
    if config.stability_views == 1 or config.stability_views < 0:
        raise AffnerfError(f"--stability-views is 0 (off) or at least 2, not {config.stability_views}")
    if config.metrics_3d and config.mesh_resolution < 2:
        raise AffnerfError(f"--mesh-resolution must be at least 2, not {config.mesh_resolution}")
    return ProtocolConfig(
        config.input_views if input_views is None else input_views,
        config.target_views,
        config.scale,
        config.seed,
        metrics_3d=config.metrics_3d,
        stability_views=config.stability_views,
    )


def run_eval(config: EvalConfig) -> dict[str, dict[str, Any]]:
    """Evaluate each method and write the outputs; returns the metrics per method label."""
    requests = method_requests(config)
    runs = parse_runs(config.runs)
    protocol_config(config)  # settings checked before anything is loaded
    ds = Dataset.open(config.data)
    objects = _objects(ds, config, max(views for _, views in requests))
    # every method is built (its run loaded and checked) before anything is written
    methods = [build_method(name, config, ds, runs.get(name)) for name, _ in requests]
    out = Path(config.out)
    out.mkdir(parents=True, exist_ok=True)
    results = {}
    for (name, views), method in zip(requests, methods, strict=True):
        label = method_label(name, views)
        protocol = protocol_config(config, views)
        started = time.perf_counter()
        result = evaluate(method, objects, protocol, config.split, len(ds.affordance_classes), config.figure_objects)
        result.method = label
        metrics = result.to_json()
        metrics["settings"] = {
            **{k: str(v) for k, v in asdict(config).items()},
            "run": str(runs.get(name, config.run)),
            "input_views": str(views),
            "seconds": round(time.perf_counter() - started, 1),
        }
        write_json_atomic(out / f"metrics_{label}.json", metrics)
        save_examples(out, label, result.examples)
        results[label] = metrics
    everything = read_method_results(out)
    main = next((r for r in everything if r["method"] == "affnerf"), results[method_label(*requests[0])])
    write_json_atomic(out / "metrics.json", main)
    (out / "table2.md").write_text(table2_markdown(everything))
    figure = figure_grid(out, [r["method"] for r in everything])
    if figure is not None:
        Image.fromarray(figure).save(out / "figure.png")
    return results
