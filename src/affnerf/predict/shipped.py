"""The models shipped with affnerf (``MODEL_CARD.md`` says how they were trained), and how a run becomes one.

Two files ship in :mod:`affnerf.weights`: the AFF-NeRF model (``affnerf-small.pt``) and the object segmenter that
``predict --segment auto`` separates cluttered photos with (``segmenter-u2netp.pt``: two U²-Net-p networks fine-tuned
on the procedural families, voting; :mod:`affnerf.model.segmenter`).

``python -m affnerf.predict.shipped RUN OUT.pt`` writes RUN's last checkpoint without its optimiser and random
states (what prediction needs, about a third of the size); the shipped model was made this way.
"""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path

import torch

from affnerf.errors import AffnerfError
from affnerf.fileio import atomic_write
from affnerf.predict.loading import resolve_checkpoint
from affnerf.train.checkpoint import inference_weights, load_checkpoint

SHIPPED_NAME = "affnerf-small.pt"
SHIPPED_SEGMENTER_NAME = "segmenter-u2netp.pt"

#: Checkpoint entries that inference reads (:func:`affnerf.predict.loading.load_model`).
INFERENCE_KEYS = (
    "format",
    "step",
    "model",
    "model_config",
    "num_classes",
    "affordance_classes",
    "background",
    "train_config",
)


def shipped_model() -> Path:
    """The shipped checkpoint's path.

    Raises:
        AffnerfError: when this installation has none (then pass ``--run``).
    """
    path = Path(str(resources.files("affnerf.weights").joinpath(SHIPPED_NAME)))
    if not path.is_file():
        raise AffnerfError(f"no --run given and no shipped model at {path}; train one with `affnerf train`")
    return path


def shipped_segmenter() -> Path | None:
    """The shipped object segmenter's path, ``None`` when this installation has none."""
    path = Path(str(resources.files("affnerf.weights").joinpath(SHIPPED_SEGMENTER_NAME)))
    return path if path.is_file() else None


def export_for_inference(run: Path, out: Path) -> Path:
    """Write the last checkpoint of ``run`` (a run folder or checkpoint file) with only the entries inference
    needs, atomically; returns ``out``. A run with an average of its weights (``--optim.ema-decay``) is exported
    with the average as its ``model``."""
    data = load_checkpoint(resolve_checkpoint(Path(run)))
    slim = {k: data[k] for k in INFERENCE_KEYS if k in data}
    slim["model"] = inference_weights(data)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(out, lambda f: torch.save(slim, f))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description="Export a run's last checkpoint for inference (no optimiser state).")
    parser.add_argument("run", type=Path, help="run folder or checkpoint file")
    parser.add_argument("out", type=Path, help="output .pt file")
    args = parser.parse_args()
    path = export_for_inference(args.run, args.out)
    print(f"{path}: {path.stat().st_size / 2**20:.1f} MB")


if __name__ == "__main__":
    main()
