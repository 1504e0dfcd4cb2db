"""Table and time-to-quality plot of an ablation ladder (``benchmarks/ablation_ladder.py``'s JSON).

    .venv/bin/python benchmarks/ladder_report.py benchmarks/results/ablation_ladder.json \\
        --curves benchmarks/results/shipped_curve.json --reference 0.30 \\
        --md benchmarks/results/ablation_ladder.md --png benchmarks/results/ablation_ladder.png

``--curves`` adds longer runs scored the same way (a JSON of ``{"runs": {name: {"curve": [...]}}}``, as the
ladder writes); ``--reference`` draws a horizontal line (the mIoU the previously shipped model reaches on the
same objects and scorer).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from PIL import Image, ImageDraw

COLOURS = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189), (140, 86, 75), (0, 0, 0)]


def markdown(runs: dict[str, Any], minutes: float) -> str:
    """The ladder as a table: each rung's steps, held-out mIoU / PSNR at the end and 3D scores."""
    lines = [
        f"Each rung adds one technique to the one above; every rung trained for {minutes:g} minutes on one core.",
        "",
        "| rung | steps | val mIoU | val PSNR | F@1cm | 3D aff. mIoU | level (/m) |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for name, run in runs.items():
        last = run["curve"][-1]
        level = run.get("calibrated_level", run["config"]["model"]["surface_density"])
        lines.append(
            f"| {name} | {run['steps']} | {last['mIoU']:.3f} | {last['PSNR']:.2f} | {run['fscore_1cm']:.3f} "
            f"| {run['affordance_miou_3d']:.3f} | {level:g} |"
        )
    return "\n".join(lines) + "\n"


def plot(curves: dict[str, list[dict[str, float]]], reference: float | None, path: Path) -> None:
    """mIoU against wall minutes, one line per run, on a white 800x500 canvas."""
    w, h, left, bottom, top, right = 800, 500, 60, 40, 20, 200
    img = Image.new("RGB", (w, h), "white")
    d = ImageDraw.Draw(img)
    xmax = max(p["seconds"] for c in curves.values() for p in c) / 60.0
    ys = [p["mIoU"] for c in curves.values() for p in c] + ([reference] if reference else [])
    ymin, ymax = min(ys) - 0.02, max(ys) + 0.02

    def xy(minutes: float, miou: float) -> tuple[float, float]:
        x = left + (w - left - right) * minutes / max(xmax, 1e-9)
        return x, h - bottom - (h - bottom - top) * (miou - ymin) / max(ymax - ymin, 1e-9)

    d.line([xy(0, ymin), xy(xmax, ymin)], fill="black")
    d.line([xy(0, ymin), xy(0, ymax)], fill="black")
    for k in range(6):
        m, v = xmax * k / 5, ymin + (ymax - ymin) * k / 5
        d.text((xy(m, ymin)[0] - 8, h - bottom + 6), f"{m:.1f}", fill="black")
        d.text((4, xy(0, v)[1] - 6), f"{v:.2f}", fill="black")
    d.text((w // 2 - 80, h - 16), "wall minutes (one core)", fill="black")
    d.text((4, 2), "held-out val mIoU", fill="black")
    if reference is not None:
        d.line([xy(0, reference), xy(xmax, reference)], fill=(160, 160, 160), width=1)
        d.text((xy(xmax, reference)[0] + 4, xy(xmax, reference)[1] - 6), "shipped before", fill=(120, 120, 120))
    for i, (name, curve) in enumerate(curves.items()):
        colour = COLOURS[i % len(COLOURS)]
        pts = [xy(p["seconds"] / 60.0, p["mIoU"]) for p in curve if p["seconds"] == p["seconds"]]
        if len(pts) > 1:
            d.line(pts, fill=colour, width=2)
        for x, y in pts:
            d.ellipse([x - 2, y - 2, x + 2, y + 2], fill=colour)
        d.text((w - right + 20, top + 16 * i), name, fill=colour)
    img.save(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ladder", type=Path)
    parser.add_argument("--curves", type=Path, nargs="*", default=[])
    parser.add_argument("--reference", type=float, default=None)
    parser.add_argument("--md", type=Path, required=True)
    parser.add_argument("--png", type=Path, required=True)
    args = parser.parse_args()
    ladder = json.loads(args.ladder.read_text())
    args.md.write_text(markdown(ladder["runs"], ladder["minutes_each"]))
    curves = {name: run["curve"] for name, run in ladder["runs"].items()}
    for extra in args.curves:
        curves.update({name: run["curve"] for name, run in json.loads(extra.read_text())["runs"].items()})
    plot(curves, args.reference, args.png)


if __name__ == "__main__":
    main()
