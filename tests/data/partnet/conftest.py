"""Fixtures of the PartNet-Mobility importer tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from affnerf.data.partnet import write_partnet_fixture


@pytest.fixture
def toy_cabinet(tmp_path: Path) -> Path:
    """A freshly written toy StorageFurniture object folder (see :mod:`affnerf.data.partnet.fixture`)."""
    return write_partnet_fixture(tmp_path / "toy_cabinet")
