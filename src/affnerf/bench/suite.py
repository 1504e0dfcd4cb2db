"""``affnerf bench``: the whole suite, written as one JSON file under ``benchmarks/results/`` and a table."""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from affnerf.bench.data_throughput import DataBenchConfig, measure_generation
from affnerf.bench.inference import measure_inference
from affnerf.bench.timing import peak_memory
from affnerf.bench.training import compare_training
from affnerf.data.dataset import Dataset
from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.environment import describe_machine
from affnerf.model.inputs import dataset_views
from affnerf.predict.loading import load_model
from affnerf.predict.predictor import pick_device
from affnerf.train.cache import cached_frames
from affnerf.train.config import PRESETS


@dataclass(frozen=True)
class BenchConfig:
    """Settings of ``affnerf bench``.

    Attributes:
        quick: a short version (under two minutes on 2 CPU cores): fewer repeats, smaller workloads.
        run: trained model for the inference measurements (default: the shipped model).
        configs: training configurations measured (comma-separated presets).
        repeats: repeats of each measurement.
        device: ``auto``, ``cpu`` or ``cuda``.
        out: output JSON (default: benchmarks/results/bench_<device>[_quick].json).
    """

    quick: bool = False
    run: Path | None = None
    configs: str = "small,paper"
    repeats: int = 5
    device: str = "auto"
    out: Path | None = None


def _frames(root: Path, crop: int, cache: Path) -> list:
    ds = Dataset.open(root)
    return [cached_frames(ds.load_object(e), cache, 0.25, crop) for e in ds.objects()]


def run_suite(config: BenchConfig) -> dict[str, Any]:
    """Run every measurement; returns the result (also written to ``config.out``)."""
    device = pick_device(config.device)
    quick = config.quick
    repeats = 3 if quick else config.repeats
    result: dict[str, Any] = {
        "benchmark": "affnerf",
        "quick": quick,
        "machine": describe_machine(),
        "settings": {k: str(v) for k, v in asdict(config).items()},
    }
    work = Path(tempfile.mkdtemp(prefix="affnerf-bench-"))
    try:
        data_cfg = DataBenchConfig(
            workers=2, objects_per_category=1 if quick else 2, views=8 if quick else 30, repeats=1 if quick else 3
        )
        result["data_generation"] = {**measure_generation(data_cfg, work), "config": asdict(data_cfg)}
        root = work / "ds"
        generate_dataset(GenerateConfig(out=root, objects_per_category=1, views=6, workers=2, seed=1), progress=False)
        result["training"] = {}
        for name in [c.strip() for c in config.configs.split(",") if c.strip()]:
            preset = PRESETS[name]
            if quick and name == "paper":  # a paper step takes seconds on a CPU: fewer rays, same sampling
                preset = replace(preset, rays_per_step=256)
            frames = _frames(root, preset.model.encoder_resolution, work / f"cache-{name}")
            steps = (3 if quick else 10) if name == "paper" and device.type == "cpu" else (5 if quick else 20)
            result["training"][name] = {
                **compare_training(preset, frames, steps, device),
                "rays_per_step": preset.rays_per_step,
            }
        result["inference"] = _inference(config, root, device, repeats, quick)
        result["memory"] = peak_memory(device)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return result


def _inference(config: BenchConfig, root: Path, device: torch.device, repeats: int, quick: bool) -> dict[str, Any]:
    from affnerf.predict.shipped import shipped_model

    run = config.run if config.run is not None else shipped_model()
    loaded = load_model(run, device)
    ds = Dataset.open(root)
    obj = ds.load_object(ds.objects()[0])
    images, _, _ = dataset_views(obj, [0], loaded.model.config)
    crop = np.round(images[0, 0].permute(1, 2, 0).numpy() * 255).astype(np.uint8)
    views, size = (5, (200, 150)) if quick else (20, (400, 300))
    return {"model": str(loaded.path), **measure_inference(loaded, crop, repeats, views, size, 128)}


def _fast_vs_reference(timing: dict[str, Any]) -> str:
    """``fast 1.73 s, reference 15.10 s: x8.8`` from a timing with fast/reference medians and a speed-up."""
    return (
        f"fast {timing['fast']['median']:.2f} s, reference {timing['reference']['median']:.2f} s: "
        f"x{timing['speedup']:.1f}"
    )


def results_table(result: dict[str, Any]) -> str:
    """The main figures as a plain-text table."""
    lines = [
        f"device: {result['machine'].get('device')}, torch {result['machine'].get('torch')}, quick={result['quick']}"
    ]
    d = result["data_generation"]
    lines.append(f"dataset rendering: {d['median']:.1f} frames/s (min {d['min']:.1f}, max {d['max']:.1f})")
    for name, t in result.get("training", {}).items():
        r, f = t["reference"], t["fast"]
        lines.append(
            f"training {name}: reference {r['rays_per_second']:.0f} rays/s ({r['points_per_second']:.3g} pts/s), "
            f"fast {f['rays_per_second']:.0f} rays/s ({f['points_per_second']:.3g} pts/s): "
            f"x{t['speedup_rays_per_second']:.1f}"
        )
    inf = result.get("inference", {})
    if inf:
        w, h = inf["size"]
        v, m = inf["image_to_view"], inf["image_to_mesh"]
        lines.append(f"image -> codes: {1000 * inf['image_to_codes']['median']:.1f} ms")
        lines.append(f"image -> one {w}x{h} view: {_fast_vs_reference(v)}")
        lines.append(f"image -> {inf['views']} views: fast {inf['image_to_views']['fast']['median']:.2f} s")
        lines.append(f"image -> mesh {inf['mesh_resolution']}^3: {_fast_vs_reference(m)}")
    mem = result.get("memory", {})
    lines.append("peak memory: " + ", ".join(f"{k} {v:.0f}" for k, v in mem.items()))
    return "\n".join(lines)
