"""Dataset rendering throughput: frames per second of ``generate_dataset`` (all four maps written to disk)."""

from __future__ import annotations

import shutil
import statistics
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from affnerf.data.generate import GenerateConfig, generate_dataset


@dataclass(frozen=True)
class DataBenchConfig:
    """A generation workload, repeated.

    Attributes:
        workers: rendering processes.
        objects_per_category: objects of each of the eight categories per run.
        views: frames per object.
        width: image width.
        height: image height.
        repeats: runs; each makes a fresh dataset in a temporary folder (process start-up included).
    """

    workers: int = 2
    objects_per_category: int = 2
    views: int = 30
    width: int = 400
    height: int = 300
    repeats: int = 3


def measure_generation(config: DataBenchConfig, scratch: Path | None = None) -> dict[str, Any]:
    """Generate the workload ``repeats`` times and report frames/s per run, their median, min and max."""
    rates = []
    for run in range(config.repeats):
        folder = Path(tempfile.mkdtemp(prefix="affnerf-bench-", dir=scratch))
        try:
            report = generate_dataset(
                GenerateConfig(
                    out=folder / "ds",
                    objects_per_category=config.objects_per_category,
                    views=config.views,
                    width=config.width,
                    height=config.height,
                    workers=config.workers,
                    seed=run,
                ),
                progress=False,
            )
            rates.append(report.frames_per_second)
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    return {
        "frames_per_run": config.objects_per_category * 8 * config.views,
        "frames_per_second": rates,
        "median": statistics.median(rates),
        "min": min(rates),
        "max": max(rates),
    }
