"""The posed baselines side by side: training rays/s and seconds per rendered view of PixelNeRF-M, Semantic-Ray
and GSNeRF in the ``small`` recipe with the same number of posed input views (3 by default).

Training: the median of ``--steps`` forward + backward + Adam steps on batches drawn up front from a tiny
generated dataset (frames at half its 200x150 resolution: the ``small`` recipe's 100x75;
:func:`affnerf.bench.training.step_throughput`), rays/s = rays per step / median step time. Rendering: one test
object encoded from its first input views, one target view at ``--scale`` of the dataset resolution (200x150 at
1.0, what ``affnerf eval --scale 0.5`` scores on 400x300 data), rendered ``--repeats`` times coarse-to-fine (as
in training) and with the occupancy grid (the fast path ``affnerf eval`` uses); median seconds per view. With
``--runs`` the views are rendered by the trained models (what ``affnerf eval`` pays); with fresh weights the fast
path skips the empty space an untrained field has, so its time is then only a lower bound. Run:

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_baselines.py --out benchmarks/results/baselines.json \
        --runs pixelnerf=RUN_PIX,semantic-ray=RUN_SEMRAY,gsnerf=RUN_GSNERF
    .venv/bin/python benchmarks/bench_baselines.py --smoke      # about 20 s, prints, writes nothing

Take timings on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import torch

from affnerf.bench.timing import timed
from affnerf.bench.training import step_throughput
from affnerf.data.dataset import Dataset
from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.environment import describe_machine
from affnerf.model.inputs import dataset_views
from affnerf.model.registry import build_model
from affnerf.model.views import render_view
from affnerf.predict.loading import load_model
from affnerf.train.cache import cached_frames
from affnerf.train.config import SMALL, TrainConfig

HERE = Path(__file__).parent
KINDS = ("pixelnerf", "semantic-ray", "gsnerf")


def dataset(root: Path, smoke: bool) -> Path:
    """A tiny dataset: 2 categories x 3 objects (train, val, test each), 12 views of 200x150 (80x60 in smoke)."""
    size = (80, 60) if smoke else (200, 150)
    config = GenerateConfig(
        out=root, categories="screwdriver,bottle", objects_per_category=3, views=12, width=size[0], height=size[1]
    )
    generate_dataset(config, progress=False)
    return root


def view_seconds(
    config: TrainConfig, data: Path, scale: float, repeats: int, weights: Path | None = None
) -> dict[str, Any]:
    """Median seconds to render one target view of a test object, coarse-to-fine and with the occupancy grid;
    with the trained model of run or checkpoint ``weights`` when given, else fresh weights."""
    torch.manual_seed(0)
    model = (load_model(weights).model if weights is not None else build_model(config.model, 12)).eval()
    ds = Dataset.open(data)
    obj = ds.load_object(ds.objects("test")[0])
    inputs = list(range(config.input_views))
    images, intr, poses = dataset_views(obj, inputs, config.model)
    k = obj.record.intrinsics.scaled(scale)
    target = obj.pose(config.input_views)
    with torch.no_grad():
        encoding = model.encode_views(images, intr, poses)
        grid = model.occupancy(encoding)
        full = timed(lambda: render_view(model, encoding, k, target), repeats)
        fast = timed(lambda: render_view(model, encoding, k, target, grid=grid), repeats)
    return {"pixels": k.width * k.height, "coarse_to_fine": full, "occupancy_grid": fast}


def measure(kind: str, data: Path, cache: Path, args: argparse.Namespace) -> dict[str, Any]:
    """Training throughput and view time of one model kind."""
    config = replace(SMALL, model=replace(SMALL.model, kind=kind), input_views=args.input_views)
    if args.smoke:
        config = replace(config, rays_per_step=64, objects_per_step=2)
    ds = Dataset.open(data)
    crop = config.model.encoder_resolution
    frames = [cached_frames(ds.load_object(e), cache, 0.5, crop) for e in ds.objects("train")]
    started = time.perf_counter()
    train = step_throughput(config, frames, args.steps, torch.device("cpu"))
    weights = args.trained.get(kind)
    render = view_seconds(config, data, args.scale, args.repeats, weights)
    return {
        "input_views": config.input_views,
        "view_weights": str(weights) if weights is not None else "fresh (untrained)",
        "rays_per_step": config.rays_per_step,
        "training": train,
        "view": render,
        "seconds": round(time.perf_counter() - started, 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--input-views", type=int, default=3)
    parser.add_argument("--steps", type=int, default=20, help="timed training steps per model")
    parser.add_argument("--repeats", type=int, default=3, help="timed renders per model and path")
    parser.add_argument("--scale", type=float, default=1.0, help="target view size, fraction of the dataset's")
    parser.add_argument("--kinds", default=",".join(KINDS))
    parser.add_argument("--smoke", action="store_true", help="a few steps on a smaller dataset; writes nothing")
    parser.add_argument("--work", type=Path, default=HERE / ".work" / "baselines")
    parser.add_argument("--out", type=Path, default=None, help="results JSON (not written in --smoke)")
    parser.add_argument(
        "--runs",
        default="",
        help="KIND=RUN,... trained runs (or checkpoints) whose weights time the views (default: fresh weights)",
    )
    args = parser.parse_args()
    args.trained = {k: Path(v) for k, _, v in (item.partition("=") for item in args.runs.split(",") if item)}
    if args.smoke:
        args.steps, args.repeats, args.scale = 2, 1, 0.25
    work = args.work / ("smoke" if args.smoke else "full")
    data = dataset(work / "data", args.smoke)
    results: dict[str, Any] = {"benchmark": "baselines", "machine": describe_machine(), "models": {}}
    for kind in args.kinds.split(","):
        results["models"][kind] = r = measure(kind, data, work / "cache", args)
        tr, view = r["training"], r["view"]
        print(
            f"{kind:13s} {r['input_views']} views: {tr['rays_per_second']:8.0f} rays/s training, "
            f"{view['coarse_to_fine']['median']:.2f} s/view coarse-to-fine, "
            f"{view['occupancy_grid']['median']:.2f} s/view with the grid ({view['pixels']} px)",
            flush=True,
        )
    if args.out is not None and not args.smoke:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=1) + "\n")
        print(f"-> {args.out}")


if __name__ == "__main__":
    main()
