"""GrabCut guided by the segmenter's probabilities (issue 16): the mean mask IoU of ``auto``'s segmenter mask on the
composite benchmark's draws (``bench_composites.py``), as the network gives it, with its edges redrawn by GrabCut
from its plain trimap, and redrawn from its probability trimap for every (band, sure background) of a grid
(:func:`affnerf.predict.grabcut.probability_trimap`). The segmenter's map is made once per composite.

Run (choose on seeds 1 and 2, check on 0, 3 and 4)::

    .venv/bin/python benchmarks/segment_refine.py --data /tmp/seg/data --seeds 1 2 --out choose.json
    .venv/bin/python benchmarks/segment_refine.py --data /tmp/seg/data --seeds 1 2 0 3 4 --bands 0.06 \
        --background 0.05 --out check.json
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np

from affnerf.data.composite import largest_component
from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import grabcut, shipped
from affnerf.predict.segment import mask_iou

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402


def variant_name(band: float, background: float) -> str:
    return f"band {band}, sure background below {background}"


def composite_scores(rgb: np.ndarray, truth: np.ndarray, model, grid: list[tuple]) -> tuple[dict, float]:
    """IoU of each variant's mask on one composite, and the seconds of the guided GrabCut (the grid's first)."""
    prob = segnet.object_probability(model, rgb)
    mask = segnet.probability_mask(prob)
    row = {"network": mask_iou(mask, truth)}
    if not mask.any():
        return {**row, "plain trimap": row["network"], **{variant_name(*g): row["network"] for g in grid}}, 0.0
    row["plain trimap"] = mask_iou(grabcut.refine_with_grabcut(rgb, mask), truth)
    secs = 0.0
    for k, (band, background) in enumerate(grid):
        start = time.perf_counter()
        labels = grabcut.probability_trimap(prob, mask, band, background)
        refined = largest_component(grabcut.grabcut_labels(rgb, labels))
        secs = time.perf_counter() - start if k == 0 else secs
        row[variant_name(band, background)] = mask_iou(refined, truth)
    return row, secs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--bands", type=float, nargs="+", default=[0.03, 0.04, 0.06, 0.08])
    parser.add_argument("--background", type=float, nargs="+", default=[0.05, 0.1, 0.25])
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    model = segnet.read_segmenter(shipped.shipped_segmenter())
    grid = list(itertools.product(args.bands, args.background))
    result = {"machine": describe_machine(), "composites": args.composites, "seeds": {}}
    for seed in args.seeds:
        rows, secs = [], []
        for c in bench_composites(args.data, seed, args.composites):
            row, sec = composite_scores(c.rgb, c.truth, model, grid)
            rows.append({"object": c.obj.record.object_id, "background": c.background, **row})
            secs.append(sec)
        names = [k for k in rows[0] if k not in ("object", "background")]
        means = {n: round(float(np.mean([r[n] for r in rows])), 4) for n in names}
        result["seeds"][str(seed)] = {"mean_iou": means, "guided_seconds_median": round(float(np.median(secs)), 3)}
        result["seeds"][str(seed)]["composites"] = rows
        print(seed, json.dumps(means), flush=True)
        args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
