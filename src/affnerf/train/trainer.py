"""The training loop: one CPU, one GPU, or many processes under ``torchrun`` (DistributedDataParallel).

A run folder holds ``config.json`` (the fully resolved config), ``checkpoints/``, ``tb/`` (TensorBoard),
``metrics.jsonl`` (one line per logged step) and, at the end, ``summary.json``. Only rank 0 writes.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch.nn.parallel import DistributedDataParallel
from tqdm import tqdm

from affnerf.data.dataset import Dataset, ObjectData
from affnerf.data.format import write_json_atomic
from affnerf.errors import AffnerfError
from affnerf.model.base import ConditionedNeRF
from affnerf.model.factory import build_model
from affnerf.train import distributed as dist_utils
from affnerf.train.cache import ObjectFrames, cached_frames
from affnerf.train.checkpoint import check_compatible, list_checkpoints, load_checkpoint, save_checkpoint
from affnerf.train.config import TrainConfig, config_to_json
from affnerf.train.loss import nerf_loss
from affnerf.train.sampler import RaySampler
from affnerf.train.validate import validate

log = logging.getLogger(__name__)


def learning_rate(config: TrainConfig, step: int) -> float:
    """Exponential decay from ``optim.lr`` at step 0 to ``optim.lr_final`` at the last step.

    Example:
        >>> from pathlib import Path
        >>> c = TrainConfig(data=Path("."), out=Path("."), steps=100)
        >>> learning_rate(c, 0), round(learning_rate(c, 100), 12)
        (0.0005, 5e-05)
    """
    frac = min(max(step / max(config.steps, 1), 0.0), 1.0)
    return config.optim.lr * (config.optim.lr_final / config.optim.lr) ** frac


@dataclass
class TrainSummary:
    """What a run reached: final step, last logged scalars, replica agreement, wall time."""

    step: int
    scalars: dict[str, float] = field(default_factory=dict)
    replicas_identical: bool = True
    seconds: float = 0.0


def _load_frames(config: TrainConfig, ds: Dataset, ctx: dist_utils.Context) -> list[ObjectFrames]:
    """Decode (once) and memory-map the training objects' frames; ranks share the decoding work."""
    entries = ds.objects("train", config.categories)
    if not entries:
        raise AffnerfError(f"{ds.root / 'dataset.json'}: no training objects (split train, categories {config.categories or 'all'})")
    cache = Path(config.cache_dir) if config.cache_dir else Path(config.out) / "cache"
    crop = config.model.encoder_resolution
    mine = entries[ctx.rank :: ctx.world]
    bar = tqdm(mine, desc="caching frames", unit="obj", disable=not (config.progress and ctx.is_main))
    for entry in bar:
        cached_frames(ds.load_object(entry), cache, config.image_scale, crop)
    dist_utils.barrier(ctx)
    return [cached_frames(ds.load_object(e), cache, config.image_scale, crop) for e in entries]


def _validation_objects(config: TrainConfig, ds: Dataset) -> list[ObjectData]:
    entries = ds.objects("val", config.categories) or ds.objects("test", config.categories)
    step = max(1, len(entries) // max(config.val_objects, 1))
    return [ds.load_object(e) for e in entries[::step][: config.val_objects]]


def _prepare_out(config: TrainConfig, ctx: dist_utils.Context) -> Path | None:
    """The checkpoint to resume from (or None); refuses to overwrite an existing run without ``--resume``."""
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


def _rank_state(sampler: RaySampler, generator: torch.Generator) -> dict[str, Any]:
    return {"sampler": sampler.state_dict(), "generator": generator.get_state(), "torch": torch.get_rng_state()}


def _params_checksum(model: torch.nn.Module) -> float:
    return float(sum(p.detach().double().abs().sum().item() for p in model.parameters()))


class _Logger:
    """Scalars and images to TensorBoard and ``metrics.jsonl`` (rank 0 only)."""

    def __init__(self, out: Path, enabled: bool) -> None:
        self.enabled = enabled
        self.writer = None
        if enabled:
            from torch.utils.tensorboard import SummaryWriter

            self.writer = SummaryWriter(str(out / "tb"))
            self.jsonl = open(out / "metrics.jsonl", "a")

    def scalars(self, step: int, values: dict[str, float]) -> None:
        if not self.enabled:
            return
        for k, v in values.items():
            self.writer.add_scalar(k, v, step)
        self.jsonl.write(json.dumps({"step": step, **values}) + "\n")
        self.jsonl.flush()

    def images(self, step: int, images: list[np.ndarray]) -> None:
        if self.enabled:
            for i, image in enumerate(images):
                self.writer.add_image(f"val/object_{i}", image, step, dataformats="HWC")

    def close(self) -> None:
        if self.enabled:
            self.writer.close()
            self.jsonl.close()


def train(config: TrainConfig) -> TrainSummary:
    """Train (or resume) a run; see the module docstring for what it writes."""
    started = time.perf_counter()
    ctx = dist_utils.setup(config.device)
    try:
        return _train(config, ctx, started)
    finally:
        dist_utils.teardown(ctx)


def _train(config: TrainConfig, ctx: dist_utils.Context, started: float) -> TrainSummary:
    ds = Dataset.open(config.data)
    resume_from = _prepare_out(config, ctx)
    dist_utils.barrier(ctx)
    frames = _load_frames(config, ds, ctx)
    num_classes = len(ds.affordance_classes)
    torch.manual_seed(config.seed)
    model = build_model(config.model, num_classes).to(ctx.device)
    optimizer = torch.optim.Adam(model.parameters(), lr=config.optim.lr)
    sampler = RaySampler(
        frames, config.objects_per_step, config.rays_per_step, config.foreground_fraction, config.seed, ctx.rank,
        ctx.world, config.input_views,
    )  # fmt: skip
    generator = torch.Generator().manual_seed(config.seed * 1000 + ctx.rank)
    step = 0
    if resume_from is not None:
        step = _restore(resume_from, model, optimizer, sampler, generator, config, num_classes, ctx)
    net: torch.nn.Module = model
    if ctx.distributed:
        net = DistributedDataParallel(model, device_ids=[ctx.device.index] if ctx.device.type == "cuda" else None)
    logger = _Logger(Path(config.out), ctx.is_main)
    val_objects = _validation_objects(config, ds) if ctx.is_main and config.val_every > 0 else []
    bar = tqdm(total=config.steps, initial=step, desc="train", unit="step", disable=not (config.progress and ctx.is_main))
    scalars: dict[str, float] = {}
    window_start, window_rays = time.perf_counter(), 0
    model.train()
    end = min(config.steps, config.stop_at) if config.stop_at > 0 else config.steps
    while step < end:
        lr = learning_rate(config, step)
        for group in optimizer.param_groups:
            group["lr"] = lr
        batch = sampler.next_batch().to(ctx.device)
        coarse, fine = net(
            batch.images, batch.input_intrinsics, batch.input_poses, batch.ray_object, batch.origins, batch.dirs,
            batch.background, True, generator,
        )  # fmt: skip
        terms = nerf_loss(coarse, fine, batch.rgb, batch.labels, config.affordance_weight)
        optimizer.zero_grad(set_to_none=True)
        terms.total.backward()
        if config.optim.grad_clip > 0:
            torch.nn.utils.clip_grad_norm_(model.parameters(), config.optim.grad_clip)
        optimizer.step()
        step += 1
        window_rays += config.rays_per_step * ctx.world
        if step % config.log_every == 0 or step == config.steps:
            final = fine if fine is not None else coarse
            stats = torch.stack(
                [terms.total, terms.mse_fine if fine is not None else terms.mse_coarse, terms.ce_fine if fine is not None else terms.ce_coarse,
                 (final.affordance.argmax(-1) == batch.labels).float().mean()]
            )  # fmt: skip
            loss, mse, ce, acc = dist_utils.mean_across(ctx, stats.detach()).tolist()
            elapsed = time.perf_counter() - window_start
            scalars = {
                "loss/total": loss,
                "loss/mse": mse,
                "loss/affordance_ce": ce,
                "train/psnr": -10.0 * math.log10(max(mse, 1e-10)),
                "train/affordance_accuracy": acc,
                "train/lr": lr,
                "perf/rays_per_second": window_rays / max(elapsed, 1e-9),
                "time/seconds": time.perf_counter() - started,
            }
            logger.scalars(step, scalars)
            bar.set_postfix(loss=f"{loss:.4f}", psnr=f"{scalars['train/psnr']:.1f}", rays_s=f"{scalars['perf/rays_per_second']:.0f}")
            window_start, window_rays = time.perf_counter(), 0
        bar.update(1)
        out_of_time = _out_of_time(config, ctx, started)
        if step % config.checkpoint_every == 0 or step == end or out_of_time:
            _save(config, ctx, step, model, optimizer, sampler, generator, num_classes, ds.affordance_classes)
        if ctx.is_main and val_objects and (step % config.val_every == 0 or step == config.steps):
            result = validate(model, val_objects, config.val_scale, chunk=config.chunk, input_views=config.input_views)
            logger.scalars(step, {"val/psnr": result.psnr, "val/affordance_miou": result.miou, "val/affordance_accuracy": result.accuracy})
            logger.images(step, result.images)
            scalars.update({"val/psnr": result.psnr, "val/affordance_miou": result.miou})
        if out_of_time:
            log.info("time limit of %.1f min reached at step %d; continue with --resume", config.time_limit, step)
            break
    bar.close()
    logger.close()
    checksums = dist_utils.gather_objects(ctx, _params_checksum(model))
    identical = all(c == checksums[0] for c in checksums)
    if not identical:
        log.warning("model replicas differ at the end of training: %s", checksums)
    summary = TrainSummary(step, scalars, identical, time.perf_counter() - started)
    if ctx.is_main:
        write_json_atomic(Path(config.out) / "summary.json", {**dataclasses.asdict(summary), "replica_checksums": checksums})
    return summary


def _out_of_time(config: TrainConfig, ctx: dist_utils.Context, started: float) -> bool:
    """Whether the time limit has passed (decided by rank 0, so all processes stop at the same step)."""
    if config.time_limit <= 0:
        return False
    late = torch.tensor(float(time.perf_counter() - started > 60.0 * config.time_limit))
    if ctx.distributed:
        torch.distributed.broadcast(late.to(ctx.device), src=0)
    return bool(late.item())


def _save(
    config: TrainConfig,
    ctx: dist_utils.Context,
    step: int,
    model: ConditionedNeRF,
    optimizer: torch.optim.Optimizer,
    sampler: RaySampler,
    generator: torch.Generator,
    num_classes: int,
    classes: list[str],
) -> None:
    states = dist_utils.gather_objects(ctx, _rank_state(sampler, generator))
    if ctx.is_main:
        payload = {
            "model": model.state_dict(),
            "optimizer": optimizer.state_dict(),
            "model_config": dataclasses.asdict(config.model),
            "num_classes": num_classes,
            "affordance_classes": list(classes),
            "background": [float(c) for c in sampler.objects[0].background],
            "train_config": config_to_json(config),
            "rank_states": states,
        }
        save_checkpoint(Path(config.out) / "checkpoints", step, payload, config.keep_checkpoints)
    dist_utils.barrier(ctx)


def _restore(
    path: Path,
    model: ConditionedNeRF,
    optimizer: torch.optim.Optimizer,
    sampler: RaySampler,
    generator: torch.Generator,
    config: TrainConfig,
    num_classes: int,
    ctx: dist_utils.Context,
) -> int:
    """Load a checkpoint into the model, optimiser and this rank's data and random state; returns its step."""
    data = load_checkpoint(path)
    check_compatible(data, config.model, num_classes, path)
    model.load_state_dict(data["model"])
    optimizer.load_state_dict(data["optimizer"])
    states = data.get("rank_states", [])
    if len(states) == ctx.world:
        state = states[ctx.rank]
        sampler.load_state_dict(state["sampler"])
        generator.set_state(state["generator"])
        torch.set_rng_state(state["torch"])
    else:
        log.warning(
            "%s: saved by %d processes, resumed by %d; data order and random state restart from the seed",
            path, len(states), ctx.world,
        )  # fmt: skip
    return int(data["step"])
