"""The shipped object segmenter's memory layout on CPU: its photo map (``photo_probability``: the whole photo and its
four tiles, each through both networks of the shipped pair, ten forward passes) with the input in PyTorch's default
NCHW layout against channels-last (NHWC, oneDNN's preferred layout for convolutions), on the composites of
``bench_segment.py``. Both layouts run on each composite in turn (order alternating), on the same threads, so the
machine's noise falls on both alike. Reported: seconds per photo, the largest difference of the two maps and the IoU
of their masks at 0.5.

    OMP_NUM_THREADS=2 .venv/bin/python benchmarks/segmenter_layout.py --data DATA [--composites 12] \\
        --out benchmarks/results/segmenter_layout.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from PIL import Image

from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import segment
from affnerf.predict.shipped import shipped_segmenter

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402

CHANNELS_LAST_PROBABILITY = segnet.object_probability


@torch.no_grad()
def nchw_probability(model: segnet.AnySegmenter, rgb: np.ndarray) -> np.ndarray:
    """``segnet.object_probability`` with the input in the default NCHW layout (the shipped code before 2026-12-07)."""
    if isinstance(model, segnet.SegmenterEnsemble):
        return segnet.vote([nchw_probability(m, rgb) for m in model.members])
    x, (w, h) = segnet.network_input(rgb, model.config)
    prob = torch.sigmoid(model(x)[0, 0, :h, :w]).numpy().astype(np.float32)
    full = Image.fromarray(prob, mode="F").resize((rgb.shape[1], rgb.shape[0]), Image.BILINEAR)
    return np.clip(np.asarray(full, np.float32), 0.0, 1.0)


def timed_map(model: segnet.AnySegmenter, rgb: np.ndarray, layout: str) -> tuple[np.ndarray, float]:
    """(H, W) photo map of ``rgb`` with the input in ``layout`` (``nchw`` or ``channels_last``), and its seconds."""
    segnet.object_probability = nchw_probability if layout == "nchw" else CHANNELS_LAST_PROBABILITY
    try:
        start = time.perf_counter()
        prob = segnet.photo_probability(model, rgb)
        return prob, time.perf_counter() - start
    finally:
        segnet.object_probability = CHANNELS_LAST_PROBABILITY


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--composites", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    model = segnet.load_segmenter(shipped_segmenter())
    timed_map(model, np.zeros((300, 400, 3), np.uint8), "nchw")  # first-call set-up costs fall on neither row
    rows = []
    for k, item in enumerate(bench_composites(args.data, args.seed, args.composites)):
        order = ("nchw", "channels_last") if k % 2 == 0 else ("channels_last", "nchw")
        maps, secs = {}, {}
        for layout in order:
            maps[layout], secs[layout] = timed_map(model, item.rgb, layout)
        rows.append({
            "seconds": secs,
            "max_abs_difference": float(np.abs(maps["nchw"] - maps["channels_last"]).max()),
            "mask_iou": segment.mask_iou(maps["nchw"] > 0.5, maps["channels_last"] > 0.5),
        })  # fmt: skip
        print(k, rows[-1], flush=True)
    summary = {
        layout: {"median_seconds": float(np.median([r["seconds"][layout] for r in rows]))}
        for layout in ("nchw", "channels_last")
    }
    summary["speedup"] = summary["nchw"]["median_seconds"] / summary["channels_last"]["median_seconds"]
    summary["max_abs_difference"] = max(r["max_abs_difference"] for r in rows)
    summary["min_mask_iou"] = min(r["mask_iou"] for r in rows)
    settings = vars(args) | {"threads": torch.get_num_threads(), "machine": describe_machine()}
    record = {"summary": summary, "composites": rows, "settings": settings}
    args.out.write_text(json.dumps(record, indent=1, default=str))
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
