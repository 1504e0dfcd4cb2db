"""Soak test: many predictions in one process keep memory flat.

Loads a model once, then predicts (encode, a turntable of views, the labelled mesh, the written folder) from the
example images in turn, recording the process's resident set size (RSS) after each prediction. Memory is flat
when the RSS after the last predictions is within a few MB of the RSS after the first round (the first round
warms allocator pools and caches).

    .venv/bin/python benchmarks/soak_predict.py [--run RUN] [--count 20] [--out benchmarks/results/soak_predict.json]
"""

from __future__ import annotations

import argparse
import gc
import json
import resource
import tempfile
import time
from pathlib import Path

import torch

from affnerf.bench.timing import peak_memory
from affnerf.demo.runner import repository_examples
from affnerf.environment import describe_machine
from affnerf.predict.outputs import PredictConfig, write_prediction
from affnerf.predict.predictor import Predictor
from affnerf.predict.shipped import shipped_model


def rss_mb() -> float:
    """Current resident set size of this process in MB (from /proc/self/statm)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * resource.getpagesize() / 2**20


def soak(run: Path, images: list[Path], count: int, views: int) -> dict:
    """Predict ``count`` times cycling over ``images``; RSS (MB) and seconds after each prediction."""
    predictor = Predictor.load(run, "cpu")
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(count):
            image = images[i % len(images)]
            start = time.perf_counter()
            write_prediction(
                predictor, PredictConfig(image=image, out=Path(tmp) / f"{i:02d}", views=views, device="cpu")
            )
            gc.collect()
            records.append({"image": image.name, "seconds": time.perf_counter() - start, "rss_mb": rss_mb()})
    first_round = records[min(len(images), count) - 1]["rss_mb"]
    last = records[-1]["rss_mb"]
    return {
        "benchmark": "soak_predict",
        "machine": describe_machine(),
        "threads": torch.get_num_threads(),
        "run": str(run),
        "count": count,
        "views_per_prediction": views,
        "rss_mb_after_first_round": first_round,
        "rss_mb_after_last": last,
        "growth_mb_after_first_round": last - first_round,
        **peak_memory("cpu"),
        "predictions": records,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=Path, default=None, help="model (default: the shipped one)")
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--views", type=int, default=4, help="turntable views per prediction")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/soak_predict.json"))
    args = parser.parse_args()
    images = sorted(repository_examples().glob("*.png"))
    result = soak(args.run or shipped_model(), images, args.count, args.views)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(
        f"RSS after the first round {result['rss_mb_after_first_round']:.1f} MB, after {args.count} predictions "
        f"{result['rss_mb_after_last']:.1f} MB (growth {result['growth_mb_after_first_round']:+.1f} MB)"
    )


if __name__ == "__main__":
    main()
