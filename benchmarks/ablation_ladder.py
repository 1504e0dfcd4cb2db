"""Ablation ladder: each technique of the quality work added one at a time to the ``small`` recipe, every rung
trained for the same wall-clock minutes on one core, then scored on held-out objects.

Rungs are cumulative, in the order of ``RUNGS`` (``today`` is the ``small`` preset as shipped before this work).
Every run keeps a checkpoint every ``--checkpoint-every`` steps; each is scored afterwards (validation split,
input view 0, ``--views`` target views at ``--scale`` of the dataset's resolution, mIoU with background over the
pooled pixels, as the trainer's validation), which with the wall time logged at that step gives the
time-to-quality curve. The final checkpoint is also scored in 3D: the labelled mesh at the model's
``surface_density`` against the true mesh (F-score at 1 cm, 3D affordance mIoU), on the same objects.
Frames and point sets are cached before any run is timed (``--cache``), so no run pays for decoding.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/ablation_ladder.py --data DATA --work WORK --minutes 7 \\
        --out benchmarks/results/ablation_ladder.json
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from affnerf.data.dataset import Dataset, ObjectData, interleave_categories
from affnerf.environment import describe_machine
from affnerf.eval.surface import sample_seed, score_mesh, true_samples
from affnerf.model.inputs import dataset_views
from affnerf.predict.loading import load_model
from affnerf.predict.mesh import model_mesh
from affnerf.train.cache import cached_frames, cached_points
from affnerf.train.config import SMALL, TrainConfig, config_to_json
from affnerf.train.trainer import train
from affnerf.train.validate import validate

#: (name, what the rung adds to the one before). ``model.X`` sets a ModelConfig field.
RUNGS: list[tuple[str, dict[str, Any]]] = [
    ("today", {}),
    ("+points", {"points_weight": 0.1}),
    ("+mask_depth", {"mask_weight": 0.1, "depth_weight": 1.0}),
    ("+film", {"model.conditioning": "film"}),
    ("+balanced_ce", {"affordance_balance": 0.5}),
    ("+jitter", {"input_jitter": 1.0}),
]


def apply(config: TrainConfig, changes: dict[str, Any]) -> TrainConfig:
    """The config with ``changes`` set (``model.X`` keys go to the model config)."""
    model = {k.split(".", 1)[1]: v for k, v in changes.items() if k.startswith("model.")}
    top = {k: v for k, v in changes.items() if not k.startswith("model.")}
    return replace(config, model=replace(config.model, **model), **top)


def ladder(base: TrainConfig) -> list[tuple[str, TrainConfig]]:
    """Every rung's full config, each adding its changes to the previous rung's."""
    out, config = [], base
    for name, changes in RUNGS:
        config = apply(config, changes)
        out.append((name, config))
    return out


def warm_cache(config: TrainConfig) -> None:
    """Decode every training object's frames and make its point set before any run is timed."""
    ds = Dataset.open(config.data)
    sigmas = (config.point_sigma_near, config.point_sigma_far)
    for entry in ds.objects("train"):
        cached_frames(ds.load_object(entry), config.cache_dir, config.image_scale, config.model)
        mesh = ds.root / entry.path / "mesh.ply"
        cached_points(mesh, entry.id, config.cache_dir, config.model.scene_half_extent, sigmas)


def heldout(data: Path, count: int) -> list[ObjectData]:
    """Up to ``count`` validation objects, taken round-robin over the categories."""
    ds = Dataset.open(data)
    return [ds.load_object(e) for e in interleave_categories(ds.objects("val"))[:count]]


@torch.no_grad()
def fscores(model: Any, objects: list[ObjectData], resolution: int) -> dict[str, float]:
    """Mean F-score at 1 cm and 3D affordance mIoU of the meshes predicted from input view 0."""
    f, miou = [], []
    for obj in objects:
        crops, intrinsics, poses = dataset_views(obj, [0], model.config)
        mesh = model_mesh(model, model.encode_views(crops, intrinsics, poses), resolution)
        score = score_mesh(mesh if len(mesh.faces) else None, true_samples(obj, 0), sample_seed(0, "ladder"))
        f.append(0.0 if score is None else score["fscore_1cm"])
        miou.append(0.0 if score is None or score["affordance_miou_3d"] is None else score["affordance_miou_3d"])
    return {"fscore_1cm": float(np.mean(f)), "affordance_miou_3d": float(np.mean(miou))}


def wall_times(run: Path) -> dict[int, float]:
    """Step -> seconds since the run started, from its logged scalars."""
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    return {r["step"]: r["time/seconds"] for r in rows if "time/seconds" in r}


def curve(run: Path, objects: list[ObjectData], views: int, scale: float, stride: int = 1) -> list[dict[str, float]]:
    """Held-out mIoU and PSNR of every ``stride``-th kept checkpoint (and the last), with the wall time the run had
    reached there."""
    times = wall_times(run)
    points = []
    kept = sorted((run / "checkpoints").glob("*.pt"))
    for ckpt in [c for i, c in enumerate(kept) if i % stride == stride - 1 or i == len(kept) - 1]:
        loaded = load_model(ckpt)
        result = validate(loaded.model.eval(), objects, scale, views_per_object=views)
        step = int(torch.load(ckpt, map_location="cpu", weights_only=False)["step"])
        near = min(times, key=lambda s: abs(s - step)) if times else step
        seconds = times.get(near, float("nan"))
        points.append({"step": step, "seconds": seconds, "mIoU": result.miou, "PSNR": result.psnr})
    return sorted(points, key=lambda p: p["step"])


def score_only(args: argparse.Namespace) -> None:
    """Score a finished run's checkpoints (its time-to-quality curve) or one checkpoint on the ladder's objects."""
    objects = heldout(args.data, args.objects)
    payload: dict[str, Any] = {"machine": describe_machine(), "heldout_objects": len(objects)}
    if args.reference:
        model = load_model(args.reference).model.eval()
        result = validate(model, objects, args.scale, views_per_object=args.views)
        payload["reference"] = {"checkpoint": str(args.reference), "mIoU": result.miou, "PSNR": result.psnr}
    if args.score_run:
        model = load_model(args.score_run).model.eval()
        summary = json.loads((args.score_run / "summary.json").read_text())
        run = {"steps": summary["step"], "train_seconds": summary["seconds"]}
        run["curve"] = curve(args.score_run, objects, args.views, args.scale, args.stride)
        payload["runs"] = {args.score_run.name: {**run, **fscores(model, objects, args.mesh_resolution)}}
    print(json.dumps(payload, indent=2)[:2000], flush=True)
    args.out.write_text(json.dumps(payload, indent=2) + "\n")


def run_parser(description: str, minutes: float) -> argparse.ArgumentParser:
    """The options every equal-time training benchmark takes: data, work and output paths, cache, minutes."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--cache", type=Path, default=None, help="frame and point cache (default: WORK/cache)")
    parser.add_argument("--minutes", type=float, default=minutes)
    return parser


def main() -> None:
    parser = run_parser(__doc__.splitlines()[0], 7.0)
    parser.add_argument("--steps", type=int, default=15_000, help="schedule length (lr decay) of every rung")
    parser.add_argument("--checkpoint-every", type=int, default=400)
    parser.add_argument("--objects", type=int, default=16, help="held-out validation objects scored")
    parser.add_argument("--views", type=int, default=2, help="target views per held-out object")
    parser.add_argument("--scale", type=float, default=0.25)
    parser.add_argument("--mesh-resolution", type=int, default=64)
    parser.add_argument("--only", nargs="*", default=None, help="run only these rungs (names)")
    parser.add_argument("--stride", type=int, default=1, help="with --score-run: score every n-th checkpoint")
    parser.add_argument("--score-run", type=Path, default=None, help="only score this finished run's checkpoints")
    parser.add_argument("--reference", type=Path, default=None, help="only score this checkpoint (the old model)")
    args = parser.parse_args()
    if args.score_run or args.reference:
        score_only(args)
        return
    base = replace(SMALL, data=args.data, steps=args.steps, time_limit=args.minutes, val_every=0, progress=False)
    base = replace(base, device="cpu", cache_dir=args.cache or args.work / "cache", out=args.work / "unused")
    base = replace(base, checkpoint_every=args.checkpoint_every, keep_checkpoints=1000)
    warm_cache(apply(base, {"points_weight": 0.1}))
    objects = heldout(args.data, args.objects)
    results: dict[str, Any] = {}
    if args.out.is_file():
        results = json.loads(args.out.read_text()).get("runs", {})
    for name, config in ladder(base):
        if args.only and name not in args.only:
            continue
        config = replace(config, out=args.work / name.strip("+"))
        started = time.perf_counter()
        summary = train(config)
        model = load_model(config.out).model.eval()
        results[name] = {
            "config": config_to_json(config),
            "steps": summary.step,
            "train_seconds": summary.seconds,
            "curve": curve(config.out, objects, args.views, args.scale),
            **fscores(model, objects, args.mesh_resolution),
            "bench_seconds": time.perf_counter() - started,
        }
        last = results[name]["curve"][-1]
        print(json.dumps({"rung": name, "steps": summary.step, **last, "F": results[name]["fscore_1cm"]}), flush=True)
        payload = {"machine": describe_machine(), "minutes_each": args.minutes, "heldout_objects": len(objects)}
        args.out.write_text(json.dumps({**payload, "runs": results}, indent=2) + "\n")


if __name__ == "__main__":
    main()
