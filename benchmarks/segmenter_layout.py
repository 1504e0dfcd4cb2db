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
from pathlib import Path

import numpy as np
import torch
from torch import nn

from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import segment
from affnerf.predict.shipped import shipped_segmenter

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402
from bench_segment import timed  # noqa: E402


class NCHWInput(nn.Module):
    """A segmenter network fed its input in the default NCHW layout, whatever layout it is given (the shipped code
    before 2026-12-07 fed NCHW; ``segnet.object_probability`` now hands the network a channels-last tensor)."""

    def __init__(self, network: segnet.Segmenter) -> None:
        super().__init__()
        self.network, self.config = network, network.config

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        return self.network(images.contiguous())


def nchw_segmenter(model: segnet.AnySegmenter) -> segnet.SegmenterEnsemble:
    """``model``'s networks, each behind :class:`NCHWInput`."""
    return segnet.SegmenterEnsemble([NCHWInput(network) for network in segnet.networks(model)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--composites", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    shipped = segnet.load_segmenter(shipped_segmenter())
    layouts = {"nchw": nchw_segmenter(shipped), "channels_last": shipped}
    segnet.photo_probability(layouts["nchw"], np.zeros((300, 400, 3), np.uint8))  # first-call set-up: in neither row
    rows = []
    for k, item in enumerate(bench_composites(args.data, args.seed, args.composites)):
        order = ("nchw", "channels_last") if k % 2 == 0 else ("channels_last", "nchw")
        maps, secs = {}, {}
        for layout in order:
            maps[layout], secs[layout] = timed(segnet.photo_probability, layouts[layout], item.rgb)
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
