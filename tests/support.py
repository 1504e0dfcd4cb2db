"""Helpers the tests import (``pythonpath = ["tests"]`` in pyproject.toml): the tiny model, command lines of tiny
runs."""

from __future__ import annotations

import importlib
from dataclasses import fields
from pathlib import Path

import numpy as np
import torch
from scipy import ndimage

from affnerf.errors import AffnerfError
from affnerf.model.config import ModelConfig
from affnerf.model.u2netp import weights_path
from affnerf.train.config import SMALL, TrainConfig

#: A model small enough to train for a few steps in a test.
TINY_MODEL = ModelConfig(
    encoder_width=0.125,
    encoder_resolution=32,
    field_width=32,
    field_depth=2,
    color_width=16,
    affordance_width=16,
    pe_xyz=6,
    pe_dir=2,
    num_coarse=16,
    num_fine=16,
    clip_to_cube=True,
)

#: Training options beyond the paper that the ``small`` preset turns on and tiny test runs may turn off.
LOSS_OPTIONS = (
    "points_weight",
    "mask_weight",
    "depth_weight",
    "termination_weight",
    "affordance_balance",
    "input_jitter",
)


def train_argv(config: TrainConfig, *extra: str) -> list[str]:
    """``affnerf train`` arguments that rebuild ``config`` from the ``small`` preset: its paths, the training
    settings tiny test runs change, and every model field that differs from the preset's; ``extra`` is appended."""
    values = {
        "data": config.data,
        "out": config.out,
        "config": "small",
        "image-scale": config.image_scale,
        "steps": config.steps,
        "checkpoint-every": config.checkpoint_every,
        "log-every": config.log_every,
        "val-every": config.val_every,
        "device": config.device,
        "rays-per-step": config.rays_per_step,
        "objects-per-step": config.objects_per_step,
    }
    for name in LOSS_OPTIONS:
        if getattr(config, name) != getattr(SMALL, name):
            values[name.replace("_", "-")] = getattr(config, name)
    if config.cache_dir is not None:
        values["cache-dir"] = config.cache_dir
    if config.init_from is not None:
        values["init-from"] = config.init_from
    for f in fields(config.model):
        value = getattr(config.model, f.name)
        if value != getattr(SMALL.model, f.name):
            values[f"model.{f.name.replace('_', '-')}"] = value
    argv = ["train", "--no-progress"]
    for name, value in values.items():
        if isinstance(value, bool):
            argv.append(f"--{name}" if value else f"--{name.replace('model.', 'model.no-', 1)}")
        else:
            argv += [f"--{name}", str(value)]
    return argv + list(extra)


def straight_and_resumed_weights(straight: TrainConfig, stop_at: int) -> tuple[dict, dict]:
    """Train ``straight`` to its end, and a copy (``<out>_halves``) stopped at ``stop_at`` then resumed; the final
    checkpoints' model weights of both (to check that resuming is exact)."""
    from dataclasses import replace

    from affnerf.train.trainer import train

    train(straight)
    halves = replace(straight, out=straight.out.parent / f"{straight.out.name}_halves", stop_at=stop_at)
    train(halves)
    train(replace(halves, stop_at=0, resume=True))
    name = f"step_{straight.steps:08d}.pt"
    a = torch.load(straight.out / "checkpoints" / name, weights_only=True)["model"]
    b = torch.load(halves.out / "checkpoints" / name, weights_only=True)["model"]
    return a, b


#: Why a test that needs the optional extra ``affnerf[segment]`` is skipped.
SEGMENT_EXTRA_MISSING = "the optional extra affnerf[segment] is not installed: make install installs it"


def salient_weights(*modules: str) -> Path | None:
    """The installed U²-Net-p ONNX file when the optional extra is there and ``modules`` import, else ``None``."""
    try:
        path = weights_path()
        for module in modules:
            importlib.import_module(module)
    except (AffnerfError, ImportError):
        return None
    return path


def disc_with_a_thin_bar(h=240, w=320, seed=0):
    """A red disc with a bar 4 pixels wide sticking out of it, on grey textured clutter: (rgb, disc, bar)."""
    rng = np.random.default_rng(seed)
    noise = ndimage.gaussian_filter(rng.normal(size=(h, w, 3)), (3, 3, 0))
    bg = 120 + 50 * noise / noise.std()
    yy, xx = np.mgrid[:h, :w]
    disc = ((yy - 120) / 50.0) ** 2 + ((xx - 200) / 50.0) ** 2 <= 1.0
    bar = (abs(yy - 120) < 2) & (xx > 40) & (xx < 160)
    rgb = np.where((disc | bar)[..., None], np.array([210, 40, 30]), bg)
    return np.clip(rgb, 0, 255).astype(np.uint8), disc, bar
