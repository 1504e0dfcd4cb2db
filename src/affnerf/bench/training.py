"""Training throughput: rays/s and field evaluations/s of forward + backward steps, reference against fast.

The reference samples like vanilla NeRF (uniform coarse samples over the whole [near, far] range, then fine
samples, every ray evaluated); the fast path samples only inside the canonical cube and skips rays that miss
it. Both run the same architecture on the same batches, side by side.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import torch

from affnerf.bench.timing import sync, timed
from affnerf.model.base import ConditionedNeRF
from affnerf.model.registry import build_model
from affnerf.train.cache import ObjectFrames
from affnerf.train.config import TrainConfig
from affnerf.train.loss import nerf_loss
from affnerf.train.sampler import RaySampler


def training_step(
    config: TrainConfig, frames: list[ObjectFrames], device: torch.device, batches: int = 0
) -> tuple[Callable[[], None], ConditionedNeRF]:
    """A closure doing one training step (forward, backward, Adam) of a fresh model of ``config``, and the model.

    With ``batches`` > 0 the steps cycle through that many batches drawn up front (the model's cost alone);
    with 0 each step draws its own batch (sampling included, as in training).
    """
    torch.manual_seed(0)
    model = build_model(config.model, 12).to(device)
    optimizer = torch.optim.Adam(model.parameters(), lr=1e-4)
    sampler = RaySampler.for_config(frames, replace(config, seed=0))
    drawn = [sampler.next_batch().to(device) for _ in range(batches)]
    generator = torch.Generator().manual_seed(0)
    position = [0]

    def step() -> None:
        b = drawn[position[0] % len(drawn)] if drawn else sampler.next_batch().to(device)
        position[0] += 1
        coarse, fine = model(
            b.images, b.input_intrinsics, b.input_poses, b.ray_object, b.origins, b.dirs, b.background, True, generator
        )
        loss = nerf_loss(coarse, fine, b.rgb, b.labels, config.affordance_weight).total
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        optimizer.step()

    return step, model


def step_throughput(
    config: TrainConfig, frames: list[ObjectFrames], steps: int, device: torch.device
) -> dict[str, Any]:
    """Seconds per training step (median of ``steps``), rays/s and field evaluations/s for one configuration."""
    step, model = training_step(config, frames, device, batches=steps + 1)
    step()
    sync(device)
    model.renderer.points_evaluated = 0
    timing = timed(step, repeats=steps, warmup=0, device=device)
    points_per_step = model.renderer.points_evaluated / steps
    return {
        "seconds_per_step": timing,
        "rays_per_second": config.rays_per_step / timing["median"],
        "points_per_second": points_per_step / timing["median"],
        "points_per_step": points_per_step,
    }


def fast_variant(config: TrainConfig, samples_scale: float = 0.5) -> TrainConfig:
    """The fast path of a configuration: samples only inside the canonical cube (rays that miss it skipped), with
    ``samples_scale`` times the samples (a ray's stretch inside the cube is about a third of [near, far], so half
    the samples there are still denser than the reference's)."""
    m = config.model
    return replace(
        config,
        model=replace(
            m,
            clip_to_cube=True,
            num_coarse=max(4, round(m.num_coarse * samples_scale)),
            num_fine=round(m.num_fine * samples_scale),
        ),
    )


def reference_variant(config: TrainConfig) -> TrainConfig:
    """The reference path of a configuration: vanilla NeRF sampling over the whole [near, far] range."""
    return replace(config, model=replace(config.model, clip_to_cube=False))


def compare_training(
    config: TrainConfig, frames: list[ObjectFrames], steps: int, device: torch.device
) -> dict[str, Any]:
    """Reference and fast throughput of one configuration (same architecture and batches)."""
    reference, fast = reference_variant(config), fast_variant(config)
    ref, fst = step_throughput(reference, frames, steps, device), step_throughput(fast, frames, steps, device)
    return {"reference": ref, "fast": fst, "speedup_rays_per_second": fst["rays_per_second"] / ref["rays_per_second"]}
