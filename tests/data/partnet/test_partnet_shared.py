"""The importer on the real PartNet-Mobility objects beside the checkout (skipped when absent)."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from affnerf.data.partnet import load_partnet_object
from affnerf.objects.asset import CANONICAL_HALF_EXTENT


def _fits(asset) -> bool:  # type: ignore[no-untyped-def]
    return bool(np.all(np.abs(asset.bounds()) <= CANONICAL_HALF_EXTENT + 1e-9))


def test_cabinet_40147(shared_partnet: Path, caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING):
        asset = load_partnet_object(shared_partnet / "40147")
    assert not caplog.records  # every leaf of the real cabinet is in the table
    assert asset.category == "cabinet" and asset.params["partnet_id"] == "40147" and _fits(asset)
    parts = {p.name: p for p in asset.parts}
    handles = [p for name, p in parts.items() if name.startswith("handle")]
    assert len(handles) == 2 and all(p.affordance == "pull" for p in handles)
    assert parts["cabinet_door_surface"].affordance == "open"
    assert parts["drawer_front"].affordance == "open"
    assert parts["other_leaf"].affordance == "support"  # through cabinet_frame
    assert {p.affordance for p in asset.parts} == {"pull", "open", "support"}
    joints = {j.type: j for j in asset.joints}
    assert sorted(joints) == ["prismatic", "revolute"]
    assert "cabinet_door_surface" in joints["revolute"].parts and "drawer_front" in joints["prismatic"].parts
    assert "cabinet_door_surface" not in joints["prismatic"].parts
    door = parts["cabinet_door_surface"]
    textures = [m.texture for m in door.materials if m.texture is not None]
    assert textures and all(t.dtype == np.uint8 and t.ndim == 3 and t.shape[2] == 3 for t in textures)
    assert door.face_uv is not None and np.isfinite(door.face_uv).all()
    # z up: the cabinet is taller than deep; its front (drawer, door) faces -y like the procedural cabinets
    lo, hi = asset.bounds()
    assert hi[2] - lo[2] > hi[1] - lo[1]
    assert parts["drawer_front"].mesh.vertices[:, 1].mean() < parts["back_panel"].mesh.vertices[:, 1].mean() - 0.1


def test_cabinet_random_pose(shared_partnet: Path) -> None:
    asset = load_partnet_object(shared_partnet / "40147", "random", np.random.default_rng(0))
    assert _fits(asset)
    assert all(j.lower <= j.value <= j.upper for j in asset.joints)


def test_bottle_3763(shared_partnet: Path) -> None:
    asset = load_partnet_object(shared_partnet / "3763")
    assert asset.category == "bottle" and _fits(asset)
    assert {p.name: p.affordance for p in asset.parts} == {"body": "grasp", "neck": "pour", "lid": "open"}
    joints = {j.type: j for j in asset.joints}
    assert sorted(joints) == ["continuous", "prismatic"]
    assert joints["continuous"].parts == ("lid",) and joints["prismatic"].parts == ("lid",)
    assert joints["prismatic"].value == pytest.approx(-0.008)  # 0 clamped into [-0.108, -0.008]
    lo, hi = asset.bounds()
    assert np.argmax(hi - lo) == 2  # standing along +z
    lid = {p.name: p for p in asset.parts}["lid"]
    assert lid.mesh.vertices[:, 2].mean() > 0.15  # on top
