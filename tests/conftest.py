"""Shared test fixtures: tiny datasets, a tiny training configuration, tiny trained runs."""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import pytest
from support import TINY_MODEL

from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.train.config import SMALL, OptimConfig, TrainConfig

REPO_ROOT = Path(__file__).resolve().parents[1]
#: Real PartNet-Mobility objects for development, beside the checkout (never copied into the repo).
SHARED_PARTNET = REPO_ROOT.parent / "shared" / "data" / "partnet-mobility"


def pytest_configure(config) -> None:
    """Under pytest-xdist (``make test`` runs a worker per core) each worker, and every process it starts, computes
    on one thread: the workers share the cores instead of fighting over them."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        import torch

        torch.set_num_threads(1)
        os.environ["OMP_NUM_THREADS"] = "1"


@pytest.fixture
def shared_partnet() -> Path:
    """The shared PartNet-Mobility folder (objects 3763, a bottle, and 40147, a cabinet), or skip."""
    if not (SHARED_PARTNET / "3763" / "mobility.urdf").is_file():
        pytest.skip(f"shared PartNet-Mobility data not found at {SHARED_PARTNET}")
    return SHARED_PARTNET


def _tiny_config(out: Path, **kwargs) -> GenerateConfig:
    """A dataset small enough to generate in about a second."""
    base = dict(out=out, categories="screwdriver,pen", objects_per_category=3, views=5, width=64, height=48, seed=3)
    base.update(kwargs)
    return GenerateConfig(**base)


@pytest.fixture(scope="session")
def tiny_config():
    """Make the settings of the tiny dataset, with overrides: ``tiny_config(out, views=6)``."""
    return _tiny_config


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("tiny") / "ds"
    generate_dataset(_tiny_config(root), progress=False)
    return root


@pytest.fixture(scope="session")
def train_dataset(tmp_path_factory) -> Path:
    """Three screwdrivers and three bottles (one each in train, val and test), 8 views of 40x30."""
    root = tmp_path_factory.mktemp("train") / "ds"
    generate_dataset(
        GenerateConfig(
            out=root, categories="screwdriver,bottle", objects_per_category=3, views=8, width=40, height=30, seed=1
        ),
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
            # a schedule for tens of steps, not the preset's 46,000 (whose 2e-5 end would stall a 50-step run)
            optim=OptimConfig(lr=1e-3, lr_final=1e-4),
            checkpoint_every=10,
            log_every=1,
            val_every=0,
            progress=False,
            device="cpu",
            cache_dir=tmp_path / "cache",
            image_scale=1.0,
            # the paper's loss and ray rule unless a test asks for more (tests/train/test_quality_options.py turns
            # them on)
            outline_fraction=0.0,
            points_weight=0.0,
            mask_weight=0.0,
            depth_weight=0.0,
            termination_weight=0.0,
            affordance_balance=0.0,
            input_jitter=0.0,
        )
        return replace(base, **overrides)

    return make


@pytest.fixture(scope="session")
def trained_runs(train_dataset, tmp_path_factory) -> dict[str, Path]:
    """A tiny AFF-NeRF run and a tiny PixelNeRF-M run (3 input views), each trained for a few steps."""
    from affnerf.train.trainer import train

    root = tmp_path_factory.mktemp("runs")
    runs = {}
    for kind, views in (("affnerf", 1), ("pixelnerf", 3)):
        config = replace(
            SMALL,
            data=train_dataset,
            out=root / kind,
            steps=30,
            model=replace(TINY_MODEL, kind=kind),
            rays_per_step=128,
            objects_per_step=2,
            input_views=views,
            checkpoint_every=30,
            log_every=10,
            val_every=0,
            progress=False,
            device="cpu",
            cache_dir=root / "cache",  # one frame and point cache for both (its entries are keyed by their settings)
            image_scale=1.0,
        )
        train(config)
        runs[kind] = config.out
    return runs


@pytest.fixture(scope="session")
def trained_segmenter(train_dataset, tmp_path_factory) -> Path:
    """An object segmenter trained for a few seconds on ``train_dataset``'s two training objects."""
    from affnerf.model.segmenter import SegmenterConfig
    from affnerf.train.segmenter import SegmenterTrainConfig, train_segmenter

    out = tmp_path_factory.mktemp("segmenter") / "segmenter.pt"
    cfg = SegmenterTrainConfig(
        data=train_dataset, out=out, steps=200, batch=8, lr=5e-3, views_per_object=8, pool=96, val_photos=16,
        network=SegmenterConfig(base=8, levels=2, input_side=48),
    )  # fmt: skip
    train_segmenter(cfg)  # seeded by cfg.seed
    return out
