"""Dataset generation throughput at 400x300 (RGB, depth, affordance and part maps written as PNG).

Run: ``.venv/bin/python benchmarks/bench_data.py [--workers 2] [--repeats 5]``; prints the result and writes
``benchmarks/results/data_throughput.json``.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict
from pathlib import Path

from affnerf.bench.data_throughput import DataBenchConfig, measure_generation
from affnerf.environment import describe_machine


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--views", type=int, default=30)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "data_throughput.json")
    args = parser.parse_args()
    config = DataBenchConfig(workers=args.workers, repeats=args.repeats, views=args.views)
    result = {"benchmark": "data_generation", "config": asdict(config), "machine": describe_machine()}
    result.update(measure_generation(config))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    rates = ", ".join(f"{r:.1f}" for r in result["frames_per_second"])
    print(f"{result['frames_per_run']} frames per run at {config.width}x{config.height}, {config.workers} workers")
    print(f"frames/s: median {result['median']:.1f} (min {result['min']:.1f}, max {result['max']:.1f}; runs {rates})")
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
