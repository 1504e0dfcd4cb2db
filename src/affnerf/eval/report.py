"""Reports of the evaluation: the markdown table laid out like the paper's Table 2, and the figure grid."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from affnerf.pictures.compose import grid, overlay_affordance, stack_rows, text_strip

#: Rows of the main table, in the paper's order.
MAIN_METRICS = ("mIoU", "PA", "MPA")
EXTRA_METRICS = ("mIoU_object", "PA_object", "MPA_object", "PSNR")


def _fmt(value: Any, best: bool) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    text = f"{value:.3f}" if abs(value) < 10 else f"{value:.2f}"
    return f"**{text}**" if best else text


def metrics_table(results: Sequence[dict[str, Any]], metrics: Sequence[str] = MAIN_METRICS) -> str:
    """A markdown table: one block of rows per metric, one row per method, one column per category and the
    average (the best value of each column in bold).

    Args:
        results: ``metrics.json`` contents (conventions §5), one per method.
        metrics: the metric keys to show.
    """
    categories = sorted({c for r in results for c in r["categories"]})
    head = "| Metric | Method | " + " | ".join(categories) + " | Average |"
    rule = "|" + " --- |" * (len(categories) + 3)
    lines = [head, rule]
    for metric in metrics:
        columns = [[r["categories"].get(c, {}).get(metric) for r in results] for c in categories]
        columns.append([r["mean"].get(metric) for r in results])
        best = [max((v for v in col if v is not None and math.isfinite(v)), default=None) for col in columns]
        for i, r in enumerate(results):
            cells = [
                _fmt(col[i], col[i] is not None and col[i] == b and len(results) > 1)
                for col, b in zip(columns, best, strict=True)
            ]
            lines.append(f"| {metric if i == 0 else ''} | {r['method']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table2_markdown(results: Sequence[dict[str, Any]], context: dict[str, Any] | None = None) -> str:
    """The full report: the main table (mIoU, PA, MPA), then object-only metrics and PSNR, and the settings."""
    split = results[0]["split"] if results else "?"
    counts = results[0]["mean"] if results else {}
    parts = [
        f"# Affordance at novel views ({split} split), laid out like the paper's Table 2",
        "",
        f"{counts.get('objects', 0)} objects, {counts.get('views', 0)} target views per method; per-category "
        "confusion matrices over all target views; classes present in the ground truth (conventions §5).",
        "",
        metrics_table(results, MAIN_METRICS),
        "",
        "Object-only variants (pixels whose ground truth is an object; background class not counted) and PSNR (dB):",
        "",
        metrics_table(results, EXTRA_METRICS),
    ]
    if context:
        parts += ["", "Settings:", "", "```", json.dumps(context, indent=1), "```"]
    return "\n".join(parts) + "\n"


def read_method_results(folder: Path) -> list[dict[str, Any]]:
    """Every ``metrics_<method>.json`` in a folder, AFF-NeRF first, then by name."""
    found = [json.loads(p.read_text()) for p in sorted(Path(folder).glob("metrics_*.json"))]
    return sorted(found, key=lambda r: (r["method"] != "affnerf", r["method"]))


def save_examples(folder: Path, method: str, examples: list[dict[str, Any]]) -> None:
    """Keep one picture per example object: its input, ground truth and this method's prediction."""
    for ex in examples:
        oid = ex["object_id"]
        rgb = np.full_like(ex["gt_rgb"], 255) if ex["rgb"] is None else np.round(ex["rgb"] * 255).astype(np.uint8)
        for sub, image in (
            ("input", ex["input"]),
            ("ground_truth", overlay_affordance(ex["gt_rgb"], ex["gt_labels"])),
            (method, overlay_affordance(rgb, ex["labels"])),
        ):
            path = Path(folder) / "examples" / sub / f"{oid}.png"
            path.parent.mkdir(parents=True, exist_ok=True)
            Image.fromarray(image).save(path)


def figure_grid(folder: Path, methods: Sequence[str]) -> np.ndarray | None:
    """(H, W, 3) grid: one row per example object, columns input | ground truth | each method."""
    examples = Path(folder) / "examples"
    ids = sorted(p.stem for p in (examples / "input").glob("*.png")) if (examples / "input").is_dir() else []
    if not ids:
        return None
    columns = ["input", "ground_truth", *[m for m in methods if (examples / m).is_dir()]]
    rows = []
    for oid in ids:
        row = []
        for col in columns:
            path = examples / col / f"{oid}.png"
            row.append(np.asarray(Image.open(path).convert("RGB")) if path.is_file() else None)
        shape = next(im.shape for im in row if im is not None)
        rows.append([im if im is not None else np.full(shape, 255, np.uint8) for im in row])
    body = grid(rows)
    header = text_strip("   |   ".join(columns), body.shape[1])
    return stack_rows([header, body])
