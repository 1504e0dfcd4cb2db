"""Reports of the evaluation: the markdown table laid out like the paper's Table 2 (with the 3D metrics and view
stability when measured), and the figure grid."""

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
#: The 3D metrics (conventions §5) and the view-stability spreads.
SURFACE_METRICS = ("chamfer_l1", "fscore_1cm", "affordance_miou_3d")
STABILITY_METRICS = ("mIoU_spread", "fscore_1cm_spread")
#: Metrics where lower is better (bold marks the smallest).
LOWER_IS_BETTER = frozenset({"chamfer_l1", "mIoU_spread", "fscore_1cm_spread"})


def _fmt(value: Any, best: bool) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    text = f"{value:.3f}" if abs(value) < 10 else f"{value:.2f}"
    return f"**{text}**" if best else text


def metrics_table(results: Sequence[dict[str, Any]], metrics: Sequence[str] = MAIN_METRICS) -> str:
    """A markdown table: one block of rows per metric, one row per method, one column per category and the
    average (the best value of each column in bold: the smallest for :data:`LOWER_IS_BETTER`).

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
        pick = min if metric in LOWER_IS_BETTER else max
        best = [pick((v for v in col if v is not None and math.isfinite(v)), default=None) for col in columns]
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
    parts += surface_section(results) + stability_section(results)
    if context:
        parts += ["", "Settings:", "", "```", json.dumps(context, indent=1), "```"]
    return "\n".join(parts) + "\n"


def surface_section(results: Sequence[dict[str, Any]]) -> list[str]:
    """Lines of the 3D table, over the methods evaluated with 3D metrics (none when there are none)."""
    measured = [r for r in results if "fscore_1cm" in r["mean"]]
    if not measured:
        return []
    return [
        "",
        "3D (conventions §5): each method's labelled mesh against the true mesh, 20,000 area-weighted surface "
        "samples each; Chamfer-L1 in metres (lower is better; over non-empty meshes), F-score at 1 cm, 3D "
        "affordance mIoU (background excluded); – where a method gives no mesh:",
        "",
        metrics_table(measured, SURFACE_METRICS),
    ]


def stability_section(results: Sequence[dict[str, Any]]) -> list[str]:
    """Lines of the view-stability table, over the methods evaluated with it (none when there are none)."""
    measured = [
        {"method": r["method"], "categories": r["stability"]["categories"], "mean": r["stability"]["mean"]}
        for r in results
        if r.get("stability")
    ]
    if not measured:
        return []
    views = sorted({r["stability"]["views"] for r in results if r.get("stability")})
    return [
        "",
        f"View stability ({', '.join(map(str, views))} input views per object): the spread (max − min) of each "
        "object's mIoU and F-score over its input views, averaged (lower is steadier):",
        "",
        metrics_table(measured, STABILITY_METRICS),
    ]


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
