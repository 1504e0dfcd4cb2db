"""A tiny dataset and a tiny configuration for training tests (seconds on 2 cores)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.model.config import ModelConfig
from affnerf.train.config import SMALL, TrainConfig

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


@pytest.fixture(scope="session")
def train_dataset(tmp_path_factory) -> Path:
    """Two screwdrivers and two bottles (so a val object exists), 8 views of 40x30."""
    root = tmp_path_factory.mktemp("train") / "ds"
    generate_dataset(
        GenerateConfig(out=root, categories="screwdriver,bottle", objects_per_category=3, views=8, width=40, height=30, seed=1),
        progress=False,
    )
    return root


@pytest.fixture
def tiny_train_config(train_dataset, tmp_path):
    """Make a tiny training config writing to a fresh run folder; keyword overrides apply."""

    def make(**overrides) -> TrainConfig:
        base = replace(
            SMALL,
            data=train_dataset,
            out=tmp_path / "run",
            steps=20,
            model=TINY_MODEL,
            rays_per_step=128,
            objects_per_step=2,
            checkpoint_every=10,
            log_every=1,
            val_every=0,
            progress=False,
            device="cpu",
            cache_dir=tmp_path / "cache",
        )
        return replace(base, **overrides)

    return make
