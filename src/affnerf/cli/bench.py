"""``affnerf bench``: the benchmark suite on this machine."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import tyro

from affnerf.bench.suite import BenchConfig


def bench(config: Annotated[BenchConfig, tyro.conf.arg(name="")]) -> None:
    """Measure dataset rendering (frames/s), training throughput (rays/s and field evaluations/s, reference vs
    fast sampling, per configuration), inference latency (image -> codes, -> one view, -> views, -> mesh at 128^3,
    reference vs fast) and peak memory, each as median/min/max over repeats. Writes JSON under
    benchmarks/results/ tagged with the device, torch version and settings, and prints a table. --quick finishes in
    under two minutes on 2 CPU cores.
    """
    from affnerf.bench.suite import results_table, run_suite

    result = run_suite(config)
    device = str(result["machine"].get("device", "cpu")).replace(" ", "_")
    out = config.out or Path("benchmarks") / "results" / f"bench_{device}{'_quick' if config.quick else ''}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(results_table(result))
    print(f"-> {out}")
