"""``affnerf train-segmenter``: train an object segmenter for ``predict --segmenter`` on a dataset's objects."""

from __future__ import annotations

import json
from typing import Annotated

import tyro

from affnerf.train.segmenter import SegmenterTrainConfig


def train_segmenter(config: Annotated[SegmenterTrainConfig, tyro.conf.arg(name="")]) -> None:
    """Train the object segmenter on a dataset's training objects pasted onto clutter.

    The objects of DATA's train split (a few views each) are pasted onto photographs bundled with scikit-image
    (except those the composite benchmark holds out), with fragments of other objects and random-shape clutter,
    and a small U-Net learns their masks. Use it for photos of your own object families: `affnerf predict --segmenter
    OUT` (with --segment auto or segmenter). Writes OUT (weights, network shape and the training record with the
    validation mask IoU, also after every 250 steps). On the procedural families, 2 CPU cores and 80 minutes gave a
    segmenter that finds the object on unseen photographs less often than GrabCut does
    (benchmarks/results/segment_composites.json): check it on your photos before relying on it.

    Exit codes: 0 done; 2 bad input (no dataset at DATA, no objects in its train split).
    """
    from affnerf.train.segmenter import train_segmenter as train

    record = train(config)
    last = record["curve"][-1] if record["curve"] else {}
    print(json.dumps({"steps": record["steps_done"], "minutes": record["minutes"], **last}))
    print(f"-> {config.out}")
