"""``affnerf train-segmenter``: train an object segmenter for ``predict --segmenter`` on a dataset's objects."""

from __future__ import annotations

import json
from typing import Annotated

import tyro

from affnerf.train.segmenter import SegmenterTrainConfig


def train_segmenter(config: Annotated[SegmenterTrainConfig, tyro.conf.arg(name="")]) -> None:
    """Train the object segmenter on a dataset's training objects pasted onto clutter.

    The objects of DATA's train split (a few views each) are pasted onto photographs bundled with scikit-image
    (except those the composite benchmark holds out) and views of the real scenes viser ships, with fragments of
    other objects, random-shape clutter and (--subjects N) whole things cut out of the photographs, and a network
    learns their masks: with --init-salient, the salient-object model's U²-Net-p fine-tuned (what pays; use --lr
    1e-4 --precision bf16 --network.input-side 256), else a small U-Net from random weights. Use it for photos of
    your own object families: `affnerf predict --segmenter OUT` (with --segment auto or segmenter). Writes OUT
    (weights, network shape and the training record with the validation mask IoU, also after every 250 steps). A
    further stage may draw part of each batch from the photos it gets most wrong (--hard-share 0.5). On the
    procedural families, 154 minutes of 2 CPU cores fine-tuning U²-Net-p in three stages, then a fourth of 50
    minutes with --hard-share 0.5, gave the two networks that ship, voting (mean mask IoU 0.85 on unseen
    photographs, against 0.54 for GrabCut; a U-Net from random weights, 80 minutes: 0.37;
    benchmarks/results/segmenter_u2netp.md; affnerf.model.segmenter.combine_segmenters makes such a pair): check
    yours on your photos before relying on it.

    Exit codes: 0 done; 2 bad input (no dataset at DATA, no objects in its train split, a --hard-share outside
    [0, 1], an --init file that holds an ensemble rather than one network).
    """
    from affnerf.train.segmenter import train_segmenter as train

    record = train(config)
    last = record["curve"][-1] if record["curve"] else {}
    print(json.dumps({"steps": record["steps_done"], "minutes": record["minutes"], **last}))
    print(f"-> {config.out}")
