"""What runs after each training iteration: logging, the progress bar, checkpoints and validation.

Every hook is called after every iteration with the same keyword arguments (see :class:`Hook`) and decides
itself whether the step is one it acts on. The trainer runs them in order: :class:`LogScalars`,
:class:`AdvanceProgress`, :class:`SaveCheckpoints`, then (rank 0 only) :class:`Validate`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Protocol

import torch
from tqdm import tqdm

from affnerf.data.dataset import ObjectData
from affnerf.model.base import ConditionedNeRF
from affnerf.train import distributed as dist_utils
from affnerf.train.config import TrainConfig
from affnerf.train.logger import MetricsLogger
from affnerf.train.validate import validate

#: What one iteration reports: 0-d detached loss tensors (``loss/total``, ``loss/mse``, ``loss/affordance_ce``,
#: ``train/affordance_accuracy``; with 3D supervision also ``loss/occupancy`` and ``loss/point_affordance``, and for
#: a signed-distance field ``loss/point_distance``; with
#: mask, depth or termination losses ``loss/mask``, ``loss/depth`` and ``loss/termination``; with the Lovász term the
#: rays' ``loss/lovasz`` (unweighted, summed over the stages); the pose-aware model's
#: ``loss/camera``; GSNeRF's ``loss/source_depth``; with two views' codes ``loss/view_consistency``; with AFF-NeRF's
#: pixel-labelling head ``loss/view_affordance``; with variational codes ``loss/code_kl``; each weighted) and
#: the learning rate it used (``train/lr``, a float; with 3D supervision the points' weight, ``train/points_weight``;
#: with depth-guided sampling its share, ``train/surface_sample_share``).
IterationOutputs = dict[str, torch.Tensor | float]


class Hook(Protocol):
    """A callable run after every iteration.

    Keyword arguments:
        step: the number of steps done (1 after the first iteration).
        outputs: what the iteration reported.
        scalars: the run's latest scalars, reported in the summary; a hook may replace or add to them.
        out_of_time: whether the time limit has passed (the run then stops after the hooks).
    """

    def __call__(
        self, *, step: int, outputs: IterationOutputs, scalars: dict[str, float], out_of_time: bool
    ) -> None: ...


def due(step: int, every: int, last: int) -> bool:
    """Whether something done every ``every`` steps (0 = only at ``last``), and at step ``last``, is done at ``step``.

    Example:
        >>> [s for s in range(1, 8) if due(s, 3, 7)]
        [3, 6, 7]
        >>> [s for s in range(1, 8) if due(s, 0, 7)]
        [7]
    """
    return (every > 0 and step % every == 0) or step == last


class LogScalars:
    """Every ``log_every`` steps and at the run's last step: losses averaged over ranks (with the 3D supervision's
    terms when the iteration reports them), training PSNR and affordance accuracy, learning rate, rays per second
    since the last log and wall time.

    They go to the logger, the progress bar's postfix, and replace the run's scalars. Every rank must run it
    (the average is a collective).
    """

    #: The outputs averaged over ranks, in this order.
    AVERAGED = ("loss/total", "loss/mse", "loss/affordance_ce", "train/affordance_accuracy")
    #: Outputs averaged and logged when an iteration reports them (3D supervision on).
    OPTIONAL = (
        "loss/occupancy",
        "loss/point_affordance",
        "loss/point_distance",
        "loss/mask",
        "loss/depth",
        "loss/termination",
        "loss/lovasz",
        "loss/camera",
        "loss/source_depth",
        "loss/view_consistency",
        "loss/view_affordance",
        "loss/code_kl",
    )

    #: The step's scheduled values (floats, the same on every rank): logged as they are, never averaged.
    SCHEDULED = ("train/lr", "train/points_weight", "train/surface_sample_share")

    def __init__(
        self, config: TrainConfig, ctx: dist_utils.Context, logger: MetricsLogger, bar: tqdm, started: float
    ) -> None:
        """Log to ``logger`` and ``bar``; ``started`` is the run's start (``time.perf_counter()``)."""
        self.every, self.last = config.log_every, config.steps
        self.rays_per_step = config.rays_per_step * ctx.world
        self.ctx, self.logger, self.bar, self.started = ctx, logger, bar, started
        self.window_start, self.window_rays = time.perf_counter(), 0

    def __call__(self, *, step: int, outputs: IterationOutputs, scalars: dict[str, float], out_of_time: bool) -> None:
        """Count the iteration's rays; on a logging step, log and restart the throughput window."""
        self.window_rays += self.rays_per_step
        if not due(step, self.every, self.last):
            return
        keys = self.AVERAGED + tuple(key for key in self.OPTIONAL if key in outputs)
        stats = torch.stack([torch.as_tensor(outputs[key]) for key in keys])  # (4,) or (6,)
        means = dict(zip(keys, dist_utils.mean_across(self.ctx, stats.detach()).tolist(), strict=True))
        loss, mse = means["loss/total"], means["loss/mse"]
        elapsed = time.perf_counter() - self.window_start
        values = {
            "loss/total": loss,
            "loss/mse": mse,
            "loss/affordance_ce": means["loss/affordance_ce"],
            **{key: means[key] for key in self.OPTIONAL if key in means},
            "train/psnr": -10.0 * math.log10(max(mse, 1e-10)),
            "train/affordance_accuracy": means["train/affordance_accuracy"],
            **{key: float(outputs[key]) for key in self.SCHEDULED if key in outputs},
            "perf/rays_per_second": self.window_rays / max(elapsed, 1e-9),
            "time/seconds": time.perf_counter() - self.started,
        }
        scalars.clear()
        scalars.update(values)
        self.logger.scalars(step, values)
        psnr, rays_s = values["train/psnr"], values["perf/rays_per_second"]
        self.bar.set_postfix(loss=f"{loss:.4f}", psnr=f"{psnr:.1f}", rays_s=f"{rays_s:.0f}")
        self.window_start, self.window_rays = time.perf_counter(), 0


class AdvanceProgress:
    """Move the progress bar on by one step."""

    def __init__(self, bar: tqdm) -> None:
        self.bar = bar

    def __call__(self, *, step: int, outputs: IterationOutputs, scalars: dict[str, float], out_of_time: bool) -> None:
        self.bar.update(1)


class SaveCheckpoints:
    """A checkpoint every ``checkpoint_every`` steps, at the end of this invocation and when out of time.

    ``save(step)`` writes it; every rank must run this hook (saving gathers each rank's state).
    """

    def __init__(self, every: int, end: int, save: Callable[[int], None]) -> None:
        """Save every ``every`` steps and at step ``end`` (``stop_at`` when set, else the run's last step)."""
        self.every, self.end, self.save = every, end, save

    def __call__(self, *, step: int, outputs: IterationOutputs, scalars: dict[str, float], out_of_time: bool) -> None:
        if due(step, self.every, self.end) or out_of_time:
            self.save(step)


class Validate:
    """Every ``val_every`` steps and at the run's last step: render the validation objects, log their PSNR,
    affordance mIoU and accuracy and one picture per object, and add ``val/psnr`` and ``val/affordance_miou``
    to the run's scalars. Rank 0 only.
    """

    def __init__(
        self, config: TrainConfig, model: ConditionedNeRF, objects: list[ObjectData], logger: MetricsLogger
    ) -> None:
        """Validate ``model`` (unwrapped) on ``objects`` at ``config.val_scale`` of their resolution."""
        self.config, self.model, self.objects, self.logger = config, model, objects, logger

    def __call__(self, *, step: int, outputs: IterationOutputs, scalars: dict[str, float], out_of_time: bool) -> None:
        config = self.config
        if not due(step, config.val_every, config.steps):
            return
        result = validate(
            self.model, self.objects, config.val_scale, chunk=config.chunk, input_views=config.input_views
        )
        self.logger.scalars(
            step,
            {"val/psnr": result.psnr, "val/affordance_miou": result.miou, "val/affordance_accuracy": result.accuracy},
        )
        self.logger.images(step, result.images)
        scalars.update({"val/psnr": result.psnr, "val/affordance_miou": result.miou})
