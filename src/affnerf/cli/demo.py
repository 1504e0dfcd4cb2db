"""``affnerf demo``: the main job on a fresh machine, end to end at a small scale."""

from __future__ import annotations

import time
from pathlib import Path


def demo(out: Path = Path("demo_out"), objects_per_category: int = 3, views: int = 12, workers: int = 2) -> None:
    """Generate a small dataset of all eight categories, then write its preview sheet and statistics.

    Args:
        out: output folder (the dataset goes to OUT/dataset).
        objects_per_category: objects of each category.
        views: views per object.
        workers: rendering processes.
    """
    from affnerf.data.format import write_json_atomic
    from affnerf.data.generate import GenerateConfig, generate_dataset
    from affnerf.data.preview import write_preview
    from affnerf.data.stats import dataset_stats

    out = Path(out)
    dataset = out / "dataset"
    t0 = time.perf_counter()
    report = generate_dataset(
        GenerateConfig(out=dataset, objects_per_category=objects_per_category, views=views, workers=workers)
    )
    print(f"[generate] {len(report.made)} objects made, {len(report.skipped)} reused, {time.perf_counter() - t0:.1f} s")
    sheet = write_preview(dataset, out / "preview.png", objects=8, views=3)
    stats = dataset_stats(dataset)
    write_json_atomic(out / "stats.json", stats.to_json())
    print(stats.table())
    print(f"dataset: {dataset}\npreview sheet: {sheet}\nstatistics: {out / 'stats.json'}")
