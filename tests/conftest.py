"""Shared test fixtures."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
#: Real PartNet-Mobility objects for development, beside the checkout (never copied into the repo).
SHARED_PARTNET = REPO_ROOT.parent / "shared" / "data" / "partnet-mobility"


@pytest.fixture
def shared_partnet() -> Path:
    """The shared PartNet-Mobility folder (objects 3763, a bottle, and 40147, a cabinet), or skip."""
    if not (SHARED_PARTNET / "3763" / "mobility.urdf").is_file():
        pytest.skip(f"shared PartNet-Mobility data not found at {SHARED_PARTNET}")
    return SHARED_PARTNET
