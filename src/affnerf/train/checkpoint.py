"""Checkpoints: written atomically (temporary file + rename), the last few kept, validated when read.

A checkpoint holds the model and optimiser states, the step, every process's random states and data position,
the resolved config and the dataset's class list, so ``--resume`` continues exactly and a model can be loaded
from its checkpoint alone.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from typing import Any

import torch

from affnerf.errors import input_error
from affnerf.fileio import atomic_write
from affnerf.model.config import NON_ARCHITECTURE_FIELDS, ModelConfig

FORMAT = "affnerf-checkpoint-1"
_NAME = re.compile(r"^step_(\d{8})\.pt$")


def checkpoint_path(folder: Path, step: int) -> Path:
    """``folder/step_00001234.pt``."""
    return Path(folder) / f"step_{step:08d}.pt"


def list_checkpoints(folder: Path) -> list[Path]:
    """Complete checkpoints in ``folder``, oldest first (temporary files are ignored)."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if _NAME.match(p.name))


def save_checkpoint(folder: Path, step: int, payload: dict[str, Any], keep: int) -> Path:
    """Write ``payload`` as the checkpoint of ``step`` and delete all but the ``keep`` newest.

    The file appears under its final name only once completely written; a failed write (full disk, read-only
    folder) raises and leaves the existing checkpoints as they were.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    target = checkpoint_path(folder, step)
    atomic_write(target, lambda f: torch.save({"format": FORMAT, "step": step, **payload}, f))
    for old in list_checkpoints(folder)[:-keep] if keep > 0 else []:
        old.unlink(missing_ok=True)
    return target


def load_checkpoint(path: Path) -> dict[str, Any]:
    """Read a checkpoint written by :func:`save_checkpoint` (on the CPU).

    Raises:
        AffnerfError: naming the file, when it is missing, truncated, corrupt or not an affnerf checkpoint.
    """
    path = Path(path)
    if not path.is_file():
        raise input_error(path, "checkpoint not found")
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises several types for damaged files
        raise input_error(
            path, f"not a readable checkpoint ({type(exc).__name__}: {' '.join(str(exc).split())[:160]})"
        ) from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        found = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise input_error(path, f"not an affnerf checkpoint (format {found!r}, expected {FORMAT!r})")
    return data


def inference_weights(data: dict[str, Any]) -> dict[str, torch.Tensor]:
    """The weights a checkpoint's model is used with: the average of its weights (``ema``, written with
    ``--optim.ema-decay``) when it has one, else the trained weights (``model``)."""
    return data.get("ema") or data["model"]


def saved_model_config(data: dict[str, Any]) -> dict[str, Any]:
    """A checkpoint's model configuration as a dict, a field it lacks (one added to :class:`ModelConfig` after it
    was made) at its default, which is what the checkpoint's model was."""
    return {**dataclasses.asdict(ModelConfig()), **data.get("model_config", {})}


def check_compatible(data: dict[str, Any], model: ModelConfig, num_classes: int, path: Path) -> None:
    """Refuse a checkpoint made with another architecture or class count, naming what differs. A field the
    checkpoint's configuration lacks (one added to :class:`ModelConfig` after it was made) counts as its default,
    which is what the checkpoint's model was."""
    saved = saved_model_config(data)
    ours = dataclasses.asdict(model)
    diff = [
        f"{k} {saved[k]!r} vs {ours[k]!r}" for k in ours if k not in NON_ARCHITECTURE_FIELDS and saved[k] != ours[k]
    ]
    if diff:
        raise input_error(path, f"checkpoint is from another configuration ({'; '.join(diff)})")
    if data.get("num_classes") != num_classes:
        raise input_error(
            path, f"checkpoint has {data.get('num_classes')} affordance classes, the dataset {num_classes}"
        )
