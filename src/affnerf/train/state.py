"""What a training checkpoint holds and how a run folder is resumed.

A checkpoint carries the model and optimiser, the model and training configs, the class list, and one entry per
rank (``rank_states``) with that rank's sampler position, forward-pass generator and torch random state, so a run
resumed by the same number of processes continues bit for bit.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from affnerf.errors import AffnerfError
from affnerf.fileio import write_json_atomic
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.train import distributed as dist_utils
from affnerf.train.checkpoint import (
    check_compatible,
    inference_weights,
    list_checkpoints,
    load_checkpoint,
    save_checkpoint,
    saved_model_config,
)
from affnerf.train.config import TrainConfig, config_to_json
from affnerf.train.ema import WeightAverage
from affnerf.train.sampler import PointSampler, RaySampler

log = logging.getLogger(__name__)


def decay_groups(model: torch.nn.Module, weight_decay: float, encoder_lr_scale: float = 1.0) -> list[dict[str, Any]]:
    """Adam's parameter groups for ``--optim.weight-decay`` and ``--optim.encoder-lr-scale``: the image encoders'
    convolution and linear weights (parameters named ``*encoder*`` with two or more dimensions) decay by
    ``weight_decay``; nothing else (the field, biases, normalisation scales) does. Each group's ``lr_scale`` (read
    by the trainer) is ``encoder_lr_scale`` for the encoders' parameters and 1 for the field's.

    Returns ``[decayed, rest]`` with a scale of 1 (the layout of runs saved before the scale), else ``[decayed,
    the encoders' rest, the field]``; any possibly empty."""
    scaled = encoder_lr_scale != 1.0
    decayed, encoder_rest, rest = [], [], []
    for name, param in model.named_parameters():
        in_encoder = "encoder" in name
        if in_encoder and param.ndim >= 2:
            decayed.append(param)
        else:
            (encoder_rest if in_encoder and scaled else rest).append(param)
    groups = [{"params": decayed, "weight_decay": weight_decay, "lr_scale": encoder_lr_scale}]
    if scaled:
        groups.append({"params": encoder_rest, "weight_decay": 0.0, "lr_scale": encoder_lr_scale})
    return [*groups, {"params": rest, "weight_decay": 0.0, "lr_scale": 1.0}]


def make_optimizer(
    model: torch.nn.Module, lr: float, device: torch.device, weight_decay: float = 0.0, encoder_lr_scale: float = 1.0
) -> torch.optim.Optimizer:
    """Adam over the model's parameters, fused on CPU and CUDA (one kernel over all parameters instead of a loop of
    small operations per parameter tensor; the same update within float rounding): on one CPU core the small
    preset's optimiser step takes about 5 ms instead of 18 (benchmarks/results/step_cost.md).

    With ``weight_decay`` > 0 it is AdamW (decoupled decay, Loshchilov & Hutter 2019) on :func:`decay_groups`;
    with only ``encoder_lr_scale`` other than 1, Adam on those groups; with neither, plain Adam with one group, as
    checkpoints written before these options hold."""
    fused = device.type in ("cpu", "cuda")
    if weight_decay <= 0 and encoder_lr_scale == 1.0:
        return torch.optim.Adam(model.parameters(), lr=lr, fused=fused)
    kind = torch.optim.AdamW if weight_decay > 0 else torch.optim.Adam
    optimizer = kind(decay_groups(model, weight_decay, encoder_lr_scale), lr=lr, fused=fused)
    for group in optimizer.param_groups:
        group["lr"] = lr * group["lr_scale"]
    return optimizer


def initial_weights(source: Path, model: ConditionedNeRF, num_classes: int) -> Path:
    """Load the weights of ``source`` (a checkpoint file, or a run folder's last checkpoint) into ``model``,
    refusing another architecture or class count; returns the checkpoint read.

    Raises:
        AffnerfError: naming the path, when it holds no checkpoint or an incompatible one.
    """
    source = Path(source)
    path = source
    if source.is_dir():
        found = list_checkpoints(source / "checkpoints") if (source / "checkpoints").is_dir() else []
        if not found:
            raise AffnerfError(f"{source}: --init-from names a folder with no checkpoints/step_*.pt")
        path = found[-1]
    data = load_checkpoint(path)
    saved = saved_model_config(data)
    shrink = model.config.coarse_field == "shared" and saved["coarse_field"] == "own" and saved["num_fine"] > 0
    base, added = grown_config(data, dataclasses.replace(model.config, coarse_field="own") if shrink else model.config)
    check_compatible(data, base, num_classes, path)
    weights = one_field_weights(inference_weights(data)) if shrink else inference_weights(data)
    if "keypoints" in added:
        weights = keypoint_head_weights(weights, model.state_dict())
    missing, unexpected = model.load_state_dict(weights, strict=not added)
    if unexpected or any(not any(part in key for part in added) for key in missing):
        raise AffnerfError(f"{path}: weights do not fit the model (missing {missing}, unexpected {unexpected})")
    if added:
        log.info("%s: grown by %s, which start where they change nothing", path, ", ".join(added))
    if shrink:
        log.info("%s: its fine field is the one field of --model.coarse-field shared", path)
    return path


def one_field_weights(weights: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """A two-field model's weights for the same model with one field for both passes (``coarse_field`` ``shared``):
    its fine field's, under the one field's names (``renderer.coarse.``); its coarse field is dropped. The meshes and
    fast renders of the two models are the same (both use the fine field); full renders differ only in where the
    fine samples go."""
    kept = {k: v for k, v in weights.items() if not k.startswith("renderer.coarse.")}
    return {k.replace("renderer.fine.", "renderer.coarse.", 1): v for k, v in kept.items()}


def keypoint_head_weights(weights: dict[str, torch.Tensor], target: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """A mean-pooling shape encoder's weights for the same encoder with ``keypoints`` pooling: its code head's
    (code_dim, C) weight gets zero columns for the keypoint features ``target``'s head reads after the C pooled ones,
    so the grown encoder gives the same code (:class:`affnerf.model.resnet.CodeEncoder`).

    Example:
        >>> w = {"shape_encoder.head.weight": torch.ones(2, 3)}
        >>> keypoint_head_weights(w, {"shape_encoder.head.weight": torch.empty(2, 5)})["shape_encoder.head.weight"]
        tensor([[1., 1., 1., 0., 0.],
                [1., 1., 1., 0., 0.]])
    """
    grown = dict(weights)
    for key in ("shape_encoder.head.weight", "shape_encoder.second_head.weight"):
        if key in weights:
            pad = target[key].shape[1] - weights[key].shape[1]
            grown[key] = torch.nn.functional.pad(weights[key], (0, pad))
    return grown


def grown_config(data: dict[str, Any], config: ModelConfig) -> tuple[ModelConfig, tuple[str, ...]]:
    """The configuration a checkpoint must match (:func:`check_compatible`) for ``config``'s model to start from
    it, and the fragments of the weight names that model may add: ``.film.`` when the checkpoint's field
    concatenates its code and ``config`` asks for FiLM, ``.label_head.`` when ``config`` gives the shape encoder a
    pixel-labelling head the checkpoint lacks, ``keypoints`` (no weight name: the shape encoder's code head widens,
    :func:`keypoint_head_weights`) when ``config`` pools the shape encoder into keypoints and the checkpoint
    averages. (Fields that do not change the weights, such as the encoders' crop
    side, may differ anyway: ``NON_ARCHITECTURE_FIELDS``.)

    Every start is exact: FiLM's modulation is zero-initialised (:class:`affnerf.model.field.Field`), the
    labelling head only adds a training loss and the keypoints enter the code with zero weights, so the grown model
    computes what the checkpoint did.
    """
    saved = data.get("model_config", {})
    added: list[str] = []
    if config.conditioning == "film" and saved.get("conditioning", "concat") == "concat":
        config = dataclasses.replace(config, conditioning="concat")
        added.append(".film.")
    if config.view_affordance_weight > 0 and not saved.get("view_affordance_weight", 0.0):
        config = dataclasses.replace(config, view_affordance_weight=0.0)
        added.append(".label_head.")
    if config.shape_pooling == "keypoints" and saved.get("shape_pooling", "mean") == "mean":
        config = dataclasses.replace(config, shape_pooling="mean")
        added.append("keypoints")
    return config, tuple(added)


def prepare_run_folder(config: TrainConfig, ctx: dist_utils.Context) -> Path | None:
    """The checkpoint to resume from (or None); refuses to overwrite an existing run without ``--resume``.

    Rank 0 also creates the run folder and writes the resolved ``config.json``.
    """
    ckpt_dir = Path(config.out) / "checkpoints"
    existing = list_checkpoints(ckpt_dir)
    if existing and not config.resume:
        raise AffnerfError(f"{config.out}: already holds a run (checkpoints/); use --resume or another --out")
    if config.resume and not existing:
        raise AffnerfError(f"{ckpt_dir}: no checkpoint to resume from")
    if ctx.is_main:
        Path(config.out).mkdir(parents=True, exist_ok=True)
        write_json_atomic(Path(config.out) / "config.json", config_to_json(config))
    return existing[-1] if config.resume else None


def params_checksum(model: torch.nn.Module) -> float:
    """Sum of the absolute values of every parameter (in float64): equal across replicas that agree."""
    return float(sum(p.detach().double().abs().sum().item() for p in model.parameters()))


@dataclass
class TrainingState:
    """The objects whose state a checkpoint saves and restores.

    Attributes:
        model: the unwrapped model (not its DistributedDataParallel wrapper).
        optimizer: its optimiser.
        sampler: this rank's ray sampler (object order, position, random draws).
        generator: this rank's generator of the forward pass's sample perturbations.
        points: this rank's sampler of 3D supervision points (None when ``points_weight`` is 0).
        ema: the average of the model's weights (None when ``optim.ema_decay`` is 0).
    """

    model: ConditionedNeRF
    optimizer: torch.optim.Optimizer
    sampler: RaySampler
    generator: torch.Generator
    points: PointSampler | None = None
    ema: WeightAverage | None = None

    def rank_state(self) -> dict[str, Any]:
        """This rank's data order and random state: sampler, forward-pass generator and torch's global RNG (and the
        point sampler's, when there is one)."""
        state = {
            "sampler": self.sampler.state_dict(),
            "generator": self.generator.get_state(),
            "torch": torch.get_rng_state(),
        }
        if self.points is not None:
            state["points"] = self.points.state_dict()
        return state

    def start_from(self, source: Path, num_classes: int) -> Path:
        """Load ``source``'s weights (:func:`initial_weights`) into the model, and start the average of the weights,
        if any, from them; returns the checkpoint read."""
        path = initial_weights(source, self.model, num_classes)
        if self.ema is not None:
            self.ema.reset(self.model)
        return path

    def save(self, config: TrainConfig, ctx: dist_utils.Context, step: int, classes: list[str]) -> None:
        """Write ``checkpoints/step_<step>.pt`` from rank 0 with every rank's state; all ranks must call it."""
        states = dist_utils.gather_objects(ctx, self.rank_state())
        if ctx.is_main:
            payload = {
                "model": self.model.state_dict(),
                "optimizer": self.optimizer.state_dict(),
                "model_config": dataclasses.asdict(config.model),
                "num_classes": len(classes),
                "affordance_classes": list(classes),
                "background": [float(c) for c in self.sampler.objects[0].background],
                "train_config": config_to_json(config),
                "rank_states": states,
            }
            if self.ema is not None:
                payload["ema"], payload["ema_updates"] = self.ema.state_dict(self.model), self.ema.updates
            save_checkpoint(Path(config.out) / "checkpoints", step, payload, config.keep_checkpoints)
        dist_utils.barrier(ctx)

    def restore(self, path: Path, config: TrainConfig, ctx: dist_utils.Context, num_classes: int) -> int:
        """Load a checkpoint into the model, optimiser and this rank's data and random state; returns its step.

        A checkpoint saved by another number of processes restores the weights and optimiser only (with a
        warning): data order and random state then restart from the seed.
        """
        data = load_checkpoint(path)
        check_compatible(data, config.model, num_classes, path)
        self.model.load_state_dict(data["model"])
        fused = self.optimizer.defaults.get("fused")
        self.optimizer.load_state_dict(data["optimizer"])
        for group in self.optimizer.param_groups:  # a checkpoint's groups carry its own (older runs: unfused)
            group["fused"] = fused
        if self.ema is not None:  # a run that had no average starts it from the weights it resumes
            self.ema.load_state_dict(data.get("ema", data["model"]), int(data.get("ema_updates", 0)))
        states = data.get("rank_states", [])
        if len(states) == ctx.world:
            state = states[ctx.rank]
            self.sampler.load_state_dict(state["sampler"])
            self.generator.set_state(state["generator"])
            torch.set_rng_state(state["torch"])
            if self.points is not None and "points" in state:
                self.points.load_state_dict(state["points"])
        else:
            log.warning(
                "%s: saved by %d processes, resumed by %d; data order and random state restart from the seed",
                path,
                len(states),
                ctx.world,
            )
        return int(data["step"])
