"""Shared test fixtures."""

from __future__ import annotations

from pathlib import Path

import pytest

from affnerf.data.generate import GenerateConfig, generate_dataset

REPO_ROOT = Path(__file__).resolve().parents[1]
#: Real PartNet-Mobility objects for development, beside the checkout (never copied into the repo).
SHARED_PARTNET = REPO_ROOT.parent / "shared" / "data" / "partnet-mobility"


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
