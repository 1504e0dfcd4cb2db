"""Loading a trained model from a run folder (its newest checkpoint) or a checkpoint file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch

from affnerf.errors import input_error
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.registry import build_model
from affnerf.train.checkpoint import inference_weights, list_checkpoints, load_checkpoint


@dataclass
class LoadedModel:
    """A trained model ready for inference.

    Attributes:
        model: the network, in evaluation mode, on its device.
        classes: affordance class names indexed by id.
        step: the training step of the checkpoint.
        path: the checkpoint file.
        train_config: the run's resolved training config (JSON form).
        background: the background colour of the training images (RGB in [0, 1]).
    """

    model: ConditionedNeRF
    classes: list[str]
    step: int
    path: Path
    train_config: dict
    background: tuple[float, float, float] = (1.0, 1.0, 1.0)

    @property
    def device(self) -> torch.device:
        return next(self.model.parameters()).device


def resolve_checkpoint(path: Path) -> Path:
    """The checkpoint file a path names: itself, or the newest in ``path/checkpoints`` (or ``path``)."""
    path = Path(path)
    if path.is_file():
        return path
    if not path.exists():
        raise input_error(path, "no such run folder or checkpoint")
    found = list_checkpoints(path / "checkpoints") or list_checkpoints(path)
    if not found:
        raise input_error(path, "no checkpoint in this run folder")
    return found[-1]


def load_model(path: Path, device: str | torch.device = "cpu") -> LoadedModel:
    """Load a trained AFF-NeRF for inference.

    Args:
        path: a run folder or a checkpoint file.
        device: where to put it.
    """
    ckpt = resolve_checkpoint(path)
    data = load_checkpoint(ckpt)
    try:
        config = ModelConfig(**data["model_config"])
        model = build_model(config, int(data["num_classes"]))
        model.load_state_dict(inference_weights(data))
    except (KeyError, TypeError, RuntimeError) as exc:
        raise input_error(
            ckpt, f"checkpoint does not match this version's model ({' '.join(str(exc).split())[:200]})"
        ) from None
    model.to(device).eval()
    background = tuple(float(c) for c in data.get("background", (1.0, 1.0, 1.0)))
    return LoadedModel(
        model, list(data["affordance_classes"]), int(data["step"]), ckpt, data.get("train_config", {}), background
    )
