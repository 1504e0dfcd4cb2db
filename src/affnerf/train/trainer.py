"""The training loop: one CPU, one GPU, or many processes under ``torchrun`` (DistributedDataParallel).

A run folder holds ``config.json`` (the fully resolved config), ``checkpoints/``, ``tb/`` (TensorBoard),
``metrics.jsonl`` (one line per logged step) and, at the end, ``summary.json``. Only rank 0 writes.

:func:`train` is the entry point. It runs a :class:`Trainer`: :meth:`Trainer.setup` builds the data, model,
optimiser and sampler and restores a checkpoint; :meth:`Trainer.train` repeats :meth:`Trainer.train_iteration`
(one optimisation step) and runs the hooks of :mod:`affnerf.train.hooks` after each (logging, progress,
checkpoints, validation); :meth:`Trainer.finish` checks the replicas agree and writes the summary.
"""

from __future__ import annotations

import dataclasses
import gc
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from torch.nn.parallel import DistributedDataParallel
from tqdm import tqdm

from affnerf.data.dataset import Dataset, ObjectData
from affnerf.fileio import write_json_atomic
from affnerf.model.base import ConditionedNeRF
from affnerf.model.field import PointGeometry
from affnerf.model.raymarch import RayOutputs
from affnerf.model.registry import build_model
from affnerf.rendering.samplers import SurfaceGuide
from affnerf.train import distributed as dist_utils
from affnerf.train.augment import jitter_crops
from affnerf.train.cache import ObjectFrames
from affnerf.train.config import TrainConfig, for_model_kind
from affnerf.train.ema import WeightAverage
from affnerf.train.hooks import AdvanceProgress, Hook, IterationOutputs, LogScalars, SaveCheckpoints, Validate
from affnerf.train.logger import MetricsLogger
from affnerf.train.loss import (
    PointWeights,
    class_weights,
    code_consistency,
    label_lovasz,
    nerf_loss,
    occupancy_slab,
    point_loss,
    ray_geometry_loss,
)
from affnerf.train.mirror import mirror_axis
from affnerf.train.options import check_options
from affnerf.train.points import DISTANCE_TRUNCATION
from affnerf.train.precision import forward_precision
from affnerf.train.run_cache import load_frames, load_points
from affnerf.train.sampler import PointBatch, PointSampler, RayBatch, RaySampler
from affnerf.train.schedule import learning_rate, points_weight, surface_sample_share
from affnerf.train.state import TrainingState, make_optimizer, params_checksum, prepare_run_folder

log = logging.getLogger(__name__)


@dataclass
class TrainSummary:
    """What a run reached: final step, last logged scalars, replica agreement, wall time."""

    step: int
    scalars: dict[str, float] = field(default_factory=dict)
    replicas_identical: bool = True
    seconds: float = 0.0


def train(config: TrainConfig) -> TrainSummary:
    """Train (or resume) a run; see the module docstring for what it writes."""
    started = time.perf_counter()
    ctx = dist_utils.setup(config.device)
    trainer = Trainer(config, ctx, started)
    try:
        trainer.setup()
        summary = trainer.train()
        dist_utils.barrier(ctx)  # no rank leaves the group while another still talks to it
        return summary
    finally:
        # Drop the DistributedDataParallel wrapper (its reducer holds the process group) and collect any cycle
        # through the trainer now: a group freed only at interpreter exit can abort a gloo rank (SIGABRT).
        trainer.__dict__.pop("net", None)
        del trainer
        gc.collect()
        dist_utils.teardown(ctx)


def label_counts(frames: list[ObjectFrames], num_classes: int) -> torch.Tensor:
    """(C,) pixels of each affordance class over every training frame (background included)."""
    counts = torch.zeros(num_classes, dtype=torch.float64)
    for f in frames:
        counts += torch.from_numpy(np.bincount(np.asarray(f.labels).reshape(-1), minlength=num_classes)[:num_classes])
    return counts


def object_backgrounds(batch: RayBatch) -> torch.Tensor:
    """(B, 3) background colour of each of the batch's objects (read off its rays)."""
    bg = torch.ones(batch.images.shape[0], 3, dtype=batch.background.dtype, device=batch.background.device)
    bg[batch.ray_object] = batch.background
    return bg


class TrainingPass(torch.nn.Module):
    """One training forward pass of a model: encode the input views, render the rays and, when points are given,
    evaluate both fields there with the same codes (one module call, so DistributedDataParallel sees it all).

    With ``consistency_weight`` > 0 the batch holds one more view per object than the model encodes
    (``encoded_views``); its codes only enter ``loss/view_consistency`` (:func:`code_consistency`, weighted)."""

    def __init__(
        self,
        model: ConditionedNeRF,
        encoded_views: int = 1,
        consistency_weight: float = 0.0,
        surface_sigma: float = 0.0,
    ) -> None:
        super().__init__()
        self.model = model
        self.encoded_views = encoded_views
        self.consistency_weight = consistency_weight
        self.surface_sigma = surface_sigma

    def forward(
        self,
        batch: RayBatch,
        generator: torch.Generator,
        points: PointBatch | None = None,
        surface_share: float = 0.0,
    ) -> tuple[RayOutputs, RayOutputs | None, list[PointGeometry] | None, dict[str, torch.Tensor]]:
        """(coarse, fine, per-field geometry at the points or None, the model's auxiliary losses), as
        ``model.forward`` + points; ``surface_share`` > 0 draws that share of the fine samples of the batch's
        surface rays around their true depth, ``surface_sigma`` apart (:class:`SurfaceGuide`)."""
        m, v = self.model, self.encoded_views
        encoding = m.encode_views(batch.images[:, :v], batch.input_intrinsics[:, :v], batch.input_poses[:, :v])
        rays = (encoding, batch.ray_object, batch.origins, batch.dirs, batch.background, True, generator)
        if surface_share > 0:
            coarse, fine = m.render_rays(*rays, guide=SurfaceGuide(batch.depth, surface_share, self.surface_sigma))
        else:
            coarse, fine = m.render_rays(*rays)
        geometry = None if points is None else m.point_geometry(encoding, points.point_object, points.points)
        auxiliary = m.auxiliary_losses(encoding, batch.input_depth[:, :v], batch.input_labels[:, :v])
        if self.consistency_weight > 0:
            other = m.encode_views(batch.images[:, v:], batch.input_intrinsics[:, v:], batch.input_poses[:, v:])
            agreement = code_consistency(encoding.shape, other.shape) + code_consistency(
                encoding.appearance, other.appearance
            )
            auxiliary["loss/view_consistency"] = self.consistency_weight * agreement / 2
        return coarse, fine, geometry, auxiliary


def _validation_objects(config: TrainConfig, ds: Dataset) -> list[ObjectData]:
    """Up to ``val_objects`` objects spread over the val split (the test split where val is empty)."""
    entries = ds.objects("val", config.categories) or ds.objects("test", config.categories)
    step = max(1, len(entries) // max(config.val_objects, 1))
    return [ds.load_object(e) for e in entries[::step][: config.val_objects]]


class Trainer:
    """One process's part of a training run.

    Attributes:
        config: the run's configuration.
        ctx: this process's rank, world size and device.
        started: the run's start (``time.perf_counter()``), for the time limit and the logged wall time.
        step: steps done so far (restored from the checkpoint when resuming).
        end: the step this invocation stops at: ``stop_at`` when set, else ``steps``.
        scalars: the latest logged scalars, reported in the summary.
        dataset, state, net, logger, bar, hooks: made by :meth:`setup`; ``net`` is the :class:`TrainingPass` of
            ``state.model``, wrapped in DistributedDataParallel when there are several processes.
    """

    dataset: Dataset
    state: TrainingState
    net: torch.nn.Module
    logger: MetricsLogger
    bar: tqdm
    hooks: list[Hook]

    def __init__(self, config: TrainConfig, ctx: dist_utils.Context, started: float | None = None) -> None:
        self.config, self.ctx = for_model_kind(config), ctx
        self.started = time.perf_counter() if started is None else started
        self.step = 0
        self.end = min(config.steps, config.stop_at) if config.stop_at > 0 else config.steps
        self.scalars: dict[str, float] = {}
        self.class_weight: torch.Tensor | None = None

    def setup(self) -> None:
        """Open the dataset, prepare the run folder, cache the training frames (and, with ``points_weight`` > 0,
        the point sets), build the model, optimiser and samplers, restore the last checkpoint when resuming (or
        load ``init_from``'s weights), and make the logger, progress bar and hooks."""
        config, ctx = self.config, self.ctx
        check_options(config)
        self.dataset = Dataset.open(config.data)
        resume_from = prepare_run_folder(config, ctx)
        dist_utils.barrier(ctx)
        frames = load_frames(config, self.dataset, ctx)
        points = load_points(config, self.dataset, ctx) if config.points_weight > 0 else {}
        axes = [mirror_axis(points[f.object_id]) for f in frames] if config.mirror_fraction > 0 else None
        if axes is not None and ctx.is_main:
            log.info(
                "mirror planes: x = 0 for %d objects, y = 0 for %d, none for %d", *(axes.count(a) for a in (0, 1, -1))
            )
        self.state = self._build_state(frames, axes)
        if config.affordance_balance > 0:
            counts = label_counts(frames, len(self.dataset.affordance_classes))
            self.class_weight = class_weights(counts, config.affordance_balance).to(ctx.device)
        if points:
            self.state.points = PointSampler(points, config.points_per_object, config.seed, ctx.rank)
        if resume_from is not None:
            self.step = self.state.restore(resume_from, config, ctx, len(self.dataset.affordance_classes))
        elif config.init_from is not None:
            source = self.state.start_from(config.init_from, len(self.dataset.affordance_classes))
            if ctx.is_main:
                log.info("started from the weights of %s", source)
        self.net = TrainingPass(
            self.state.model, config.input_views, config.view_consistency_weight, config.surface_sample_sigma
        )
        if ctx.distributed:
            device_ids = [ctx.device.index] if ctx.device.type == "cuda" else None
            self.net = DistributedDataParallel(self.net, device_ids=device_ids)
        self.hooks = self._make_hooks()
        self.state.model.train()

    def _build_state(self, frames: list[ObjectFrames], mirror_axes: list[int] | None = None) -> TrainingState:
        """The model (initialised from ``seed``), Adam, this rank's ray sampler (with each object's mirror axis
        when ``mirror_fraction`` > 0) and forward-pass generator."""
        config, ctx = self.config, self.ctx
        torch.manual_seed(config.seed)
        model = build_model(config.model, len(self.dataset.affordance_classes)).to(ctx.device)
        optim = config.optim
        optimizer = make_optimizer(model, optim.lr, ctx.device, optim.weight_decay, optim.encoder_lr_scale)
        sampler = RaySampler.for_config(frames, config, ctx.rank, ctx.world, mirror_axes)
        generator = torch.Generator().manual_seed(config.seed * 1000 + ctx.rank)
        ema = WeightAverage(model, config.optim.ema_decay) if config.optim.ema_decay > 0 else None
        return TrainingState(model, optimizer, sampler, generator, ema=ema)

    def _make_hooks(self) -> list[Hook]:
        """The logger, the progress bar and the hooks run after each iteration, in the order they run."""
        config, ctx = self.config, self.ctx
        self.logger = MetricsLogger(Path(config.out), ctx.is_main)
        val_objects = _validation_objects(config, self.dataset) if ctx.is_main and config.val_every > 0 else []
        show = config.progress and ctx.is_main
        self.bar = tqdm(total=config.steps, initial=self.step, desc="train", unit="step", disable=not show)
        hooks: list[Hook] = [
            LogScalars(config, ctx, self.logger, self.bar, self.started),
            AdvanceProgress(self.bar),
            SaveCheckpoints(config.checkpoint_every, self.end, self.save_checkpoint),
        ]
        if val_objects:
            hooks.append(Validate(config, self.state.model, val_objects, self.logger))
        return hooks

    def train(self) -> TrainSummary:
        """Iterate from the current step to :attr:`end`, running the hooks after each iteration; stop early, with a
        checkpoint, once the time limit has passed. Returns the run's summary."""
        while self.step < self.end:
            outputs = self.train_iteration(self.step)
            self.step += 1
            out_of_time = self.out_of_time()
            self.after_iteration(outputs, out_of_time)
            if out_of_time:
                minutes = self.config.time_limit
                log.info("time limit of %.1f min reached at step %d; continue with --resume", minutes, self.step)
                break
        return self.finish()

    def train_iteration(self, step: int) -> IterationOutputs:
        """One optimisation step taken at ``step`` (steps done so far, 0-based).

        Sets the learning rate, draws a batch (B = ``objects_per_step`` objects, R = ``rays_per_step`` rays, and
        with ``points_weight`` > 0, ``points_per_object`` points of each object), renders the R rays coarse and
        fine from the B objects' encoded views (forward pass and loss in the run's ``precision``), back-propagates
        the loss and steps Adam. Returns 0-d detached tensors: ``loss/total``, and ``loss/mse``,
        ``loss/affordance_ce`` and ``train/affordance_accuracy`` of the finest pass (the fine one, the coarse one in
        a coarse-only model), with the ``train/lr`` used (a float); with points, also ``loss/occupancy`` and
        ``loss/point_affordance`` (and a signed-distance field's ``loss/point_distance``) of the finest field and the
        step's μ (``train/points_weight``, a float); with depth-guided sampling its share
        (``train/surface_sample_share``, a float); and the
        model's auxiliary losses (the pose-aware model's ``loss/camera``, GSNeRF's ``loss/source_depth``).
        """
        config, state = self.config, self.state
        lr = learning_rate(config, step)
        for group in state.optimizer.param_groups:  # the encoders' groups may scale it (--optim.encoder-lr-scale)
            group["lr"] = lr * group.get("lr_scale", 1.0)
        batch = state.sampler.next_batch().to(self.ctx.device)
        if config.input_jitter > 0:
            images, intrinsics = jitter_crops(
                batch.images, batch.input_intrinsics, object_backgrounds(batch), config.input_jitter, state.generator
            )
            batch = dataclasses.replace(batch, images=images, input_intrinsics=intrinsics)
        points = None
        if state.points is not None:
            points = state.points.draw(batch.object_ids, batch.reflect.cpu().numpy()).to(self.ctx.device)
        mu = points_weight(config, step)
        share = surface_sample_share(config, step)
        with forward_precision(config.precision, self.ctx.device):
            total, outputs = self._loss(batch, points, mu, share)
        state.optimizer.zero_grad(set_to_none=True)
        total.backward()
        if config.optim.grad_clip > 0:
            torch.nn.utils.clip_grad_norm_(state.model.parameters(), config.optim.grad_clip)
        state.optimizer.step()
        if state.ema is not None:
            state.ema.update(state.model)
        scheduled = {"train/lr": lr} if points is None else {"train/lr": lr, "train/points_weight": mu}
        if config.surface_sample_share > 0:
            scheduled["train/surface_sample_share"] = share
        return {"loss/total": total.detach(), **outputs, **scheduled}

    def _loss(
        self, batch: RayBatch, points: PointBatch | None, mu: float, surface_share: float = 0.0
    ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """The step's total loss and its detached parts (see :meth:`train_iteration`); ``mu``: the points' weight;
        ``surface_share``: the step's share of fine samples drawn around the true surface."""
        config = self.config
        coarse, fine, geometry, auxiliary = self.net(batch, self.state.generator, points, surface_share)
        terms = nerf_loss(coarse, fine, batch.rgb, batch.labels, config.affordance_weight, self.class_weight)
        final = fine if fine is not None else coarse  # affordance (R, C) class probabilities
        parts = {
            "loss/mse": (terms.mse_fine if fine is not None else terms.mse_coarse).detach(),
            "loss/affordance_ce": (terms.ce_fine if fine is not None else terms.ce_coarse).detach(),
            "train/affordance_accuracy": (final.affordance.detach().argmax(-1) == batch.labels).float().mean(),
        }
        total = terms.total
        for name, term in auxiliary.items():  # the model's own (pose-aware camera, GSNeRF source depth), as weighted
            parts[name] = term.detach()
            total = total + term
        stages = [coarse] if fine is None else [coarse, fine]
        weights = (config.mask_weight, config.depth_weight, config.termination_weight)
        if any(w > 0 for w in weights):
            rays = ray_geometry_loss(stages, batch.labels, batch.depth, weights)
            parts["loss/mask"], parts["loss/depth"] = rays.mask.detach(), rays.depth.detach()
            parts["loss/termination"] = rays.termination.detach()
            total = total + rays.total
        if config.lovasz_weight > 0:  # the points' term weighted as their cross-entropy is
            on_rays, on_points = label_lovasz(stages, batch.labels, geometry, None if points is None else points.labels)
            parts["loss/lovasz"] = on_rays.detach()
            point_weight = mu * config.point_affordance_weight
            total = total + config.lovasz_weight * (config.affordance_weight * on_rays + point_weight * on_points)
        if points is None or geometry is None:
            return total, parts
        weights = PointWeights(
            mu,
            config.point_affordance_weight,
            config.point_distance_weight,
            occupancy_slab(config.model.surface_density),
            DISTANCE_TRUNCATION,
            self.class_weight,
        )
        extra = point_loss(geometry, points, weights)
        parts["loss/occupancy"] = extra.occupancy_last.detach()
        parts["loss/point_affordance"] = extra.affordance_last.detach()
        if config.model.geometry == "sdf":
            parts["loss/point_distance"] = extra.distance_last.detach()
        return total + extra.total, parts

    def after_iteration(self, outputs: IterationOutputs, out_of_time: bool) -> None:
        """Run every hook, in order, with the step just done, the iteration's outputs and the run's scalars."""
        for hook in self.hooks:
            hook(step=self.step, outputs=outputs, scalars=self.scalars, out_of_time=out_of_time)

    def out_of_time(self) -> bool:
        """Whether the time limit has passed (decided by rank 0, so all processes stop at the same step)."""
        if self.config.time_limit <= 0:
            return False
        late = torch.tensor(float(time.perf_counter() - self.started > 60.0 * self.config.time_limit))
        if self.ctx.distributed:
            late = late.to(self.ctx.device)  # a new tensor on a GPU: broadcast into the one that is read back
            torch.distributed.broadcast(late, src=0)
        return bool(late.item())

    def save_checkpoint(self, step: int) -> None:
        """Write the checkpoint of ``step`` (rank 0) with every rank's data and random state; all ranks call it."""
        self.state.save(self.config, self.ctx, step, self.dataset.affordance_classes)

    def finish(self) -> TrainSummary:
        """Close the bar and logger, compare the replicas' parameter checksums, and write ``summary.json``."""
        self.bar.close()
        self.logger.close()
        checksums = dist_utils.gather_objects(self.ctx, params_checksum(self.state.model))
        identical = all(c == checksums[0] for c in checksums)
        if not identical:
            log.warning("model replicas differ at the end of training: %s", checksums)
        summary = TrainSummary(self.step, self.scalars, identical, time.perf_counter() - self.started)
        if self.ctx.is_main:
            payload = {**dataclasses.asdict(summary), "replica_checksums": checksums}
            write_json_atomic(Path(self.config.out) / "summary.json", payload)
        return summary
