"""Loading the toy cabinet: parts, affordances, joints, poses, textures, and errors naming the file."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest

from affnerf.data.partnet import load_partnet_object, write_partnet_fixture
from affnerf.data.partnet.fixture import DOOR_LIMITS, DRAWER_LIMITS
from affnerf.errors import AffnerfError
from affnerf.objects.asset import CANONICAL_HALF_EXTENT, NORMALISED_EXTENT, merge_parts

EXPECTED_PARTS = {
    "other_leaf": "support",  # only through its ancestor cabinet_frame
    "back_panel": "support",
    "cabinet_door_surface": "open",
    "handle_8": "pull",
    "drawer_front": "open",
    "drawer_bottom": "open",
    "handle_13": "pull",
}


def test_parts_and_affordances(toy_cabinet: Path, caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING):
        asset = load_partnet_object(toy_cabinet)
    assert {p.name: p.affordance for p in asset.parts} == EXPECTED_PARTS
    assert [p.name for p in asset.parts] == list(EXPECTED_PARTS)  # result.json order
    assert not caplog.records  # every leaf is mapped, every visual is listed
    assert asset.category == "cabinet" and asset.source == "partnet-mobility"
    assert asset.params == {"partnet_id": "toy_cabinet", "model_cat": "StorageFurniture", "joint_state": "rest"}
    assert all(len(p.mesh.faces) == 12 for p in asset.parts)


def test_fits_the_canonical_cube(toy_cabinet: Path) -> None:
    asset = load_partnet_object(toy_cabinet)
    lo, hi = asset.bounds()
    assert np.all(np.abs(asset.bounds()) <= CANONICAL_HALF_EXTENT + 1e-9)
    assert np.allclose((lo + hi) / 2, 0) and np.isclose(np.max(hi - lo), NORMALISED_EXTENT)
    # the toy is 0.8 m tall (z after the base joint): 0.44 / 0.8
    assert asset.scale == pytest.approx(NORMALISED_EXTENT / 0.8)
    assert np.argmax(hi - lo) == 2
    surface = merge_parts(asset)
    assert surface.face_part.max() == len(asset.parts)


def test_joint_states_recorded_within_limits(toy_cabinet: Path) -> None:
    for mode, rng in (("rest", None), ("random", np.random.default_rng(1))):
        joints = {j.name: j for j in load_partnet_object(toy_cabinet, mode, rng).joints}
        assert set(joints) == {"joint_0", "joint_1"}  # the fixed base joint is not recorded
        door, drawer = joints["joint_0"], joints["joint_1"]
        assert (door.type, (door.lower, door.upper)) == ("revolute", pytest.approx(DOOR_LIMITS))
        assert (drawer.type, (drawer.lower, drawer.upper)) == ("prismatic", pytest.approx(DRAWER_LIMITS))
        assert door.parts == ("cabinet_door_surface", "handle_8")
        assert drawer.parts == ("drawer_front", "drawer_bottom", "handle_13")
        for j in (door, drawer):
            assert j.lower <= j.value <= j.upper
            assert json.loads(json.dumps(j.to_json()))["limits"] == [j.lower, j.upper]
        if mode == "rest":
            assert door.value == 0.0 and drawer.value == 0.0


def test_rest_and_random_poses_differ_for_the_door(toy_cabinet: Path) -> None:
    rest = load_partnet_object(toy_cabinet)
    opened = load_partnet_object(toy_cabinet, "random", np.random.default_rng(1))
    again = load_partnet_object(toy_cabinet, "random", np.random.default_rng(1))
    door = {
        a: {p.name: p for p in asset.parts}["cabinet_door_surface"]
        for a, asset in (("rest", rest), ("open", opened), ("again", again))
    }
    assert not np.allclose(door["rest"].mesh.vertices, door["open"].mesh.vertices, atol=1e-3)
    assert np.array_equal(door["open"].mesh.vertices, door["again"].mesh.vertices)
    # at rest the door is closed: flush with the drawer front on the object's front (-y, after the yaw) side
    drawer = {p.name: p for p in rest.parts}["drawer_front"]
    assert door["rest"].mesh.vertices[:, 1].min() == pytest.approx(drawer.mesh.vertices[:, 1].min())
    assert door["rest"].mesh.vertices[:, 1].min() < rest.bounds().mean(axis=0)[1]
    assert opened.params["joint_state"] == "random"


def test_textured_part(toy_cabinet: Path) -> None:
    asset = load_partnet_object(toy_cabinet)
    door = {p.name: p for p in asset.parts}["cabinet_door_surface"]
    assert door.face_uv is not None and door.face_uv.shape == (12, 3, 2)
    assert door.face_uv.min() >= 0.0 and door.face_uv.max() <= 1.0
    assert door.face_material is not None
    textured = [m for m in door.materials if m.texture is not None]
    assert len(textured) == 1 and textured[0].texture.shape == (8, 8, 3) and textured[0].texture.dtype == np.uint8
    assert {p.name: p for p in asset.parts}["handle_8"].face_uv is None


def test_malformed_limit_is_tolerated(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    src = write_partnet_fixture(tmp_path / "obj", malformed_limit=True)
    with caplog.at_level(logging.WARNING):
        asset = load_partnet_object(src)
    drawer = {j.name: j for j in asset.joints}["joint_1"]
    assert drawer.lower == pytest.approx(-0.008) and drawer.value == 0.0
    assert any("mobility.urdf" in r.getMessage() and "-z0.008" in r.getMessage() for r in caplog.records)


def test_unmapped_leaf_warns_or_fails_with_strict(toy_cabinet: Path, caplog: pytest.LogCaptureFixture) -> None:
    result = toy_cabinet / "result.json"
    result.write_text(result.read_text().replace('"cabinet_frame"', '"mystery"'))
    with caplog.at_level(logging.WARNING):
        asset = load_partnet_object(toy_cabinet)
    assert {p.name: p.affordance for p in asset.parts}["other_leaf"] == "support"  # the default
    assert "'other_leaf'" in caplog.text and "result.json" in caplog.text
    with pytest.raises(AffnerfError, match=r"result.json: part 'other_leaf'"):
        load_partnet_object(toy_cabinet, strict=True)


def test_user_mapping_overrides(toy_cabinet: Path, tmp_path: Path) -> None:
    user = tmp_path / "mine.yaml"
    user.write_text("StorageFurniture:\n  category: cabinet\n  parts:\n    handle: grasp\n")
    asset = load_partnet_object(toy_cabinet, mapping=user)
    assert {p.name: p.affordance for p in asset.parts}["handle_8"] == "grasp"


def _bad(tmp_path: Path, kind: str) -> tuple[Path, str]:
    """A broken fixture and the file name its error must name."""
    if kind == "missing_obj":
        return write_partnet_fixture(tmp_path / "o", missing_obj=True), "original-7.obj"
    if kind == "nonfinite":
        return write_partnet_fixture(tmp_path / "o", nonfinite_vertex=True), "original-1.obj"
    if kind == "model_cat":
        return write_partnet_fixture(tmp_path / "o", model_cat="Toaster"), "meta.json"
    src = write_partnet_fixture(tmp_path / "o")
    if kind == "xml":
        (src / "mobility.urdf").write_text("<robot><link name='base'>")
        return src, "mobility.urdf"
    if kind == "limit":
        urdf = src / "mobility.urdf"
        urdf.write_text(urdf.read_text().replace('upper="0.3"', 'upper="open"'))
        return src, "mobility.urdf"
    if kind == "result":
        (src / "result.json").write_text('[{"name": "no id"}]')
        return src, "result.json"
    if kind == "no_meta":
        (src / "meta.json").unlink()
        return src, "meta.json"
    if kind == "mapping":
        return src, "bad.yaml"
    raise AssertionError(kind)


@pytest.mark.parametrize(
    "kind", ["missing_obj", "nonfinite", "model_cat", "xml", "limit", "result", "no_meta", "mapping"]
)
def test_bad_inputs_name_the_file(tmp_path: Path, kind: str) -> None:
    src, name = _bad(tmp_path, kind)
    mapping = None
    if kind == "mapping":
        mapping = tmp_path / "bad.yaml"
        mapping.write_text("StorageFurniture:\n  parts:\n    handle: yank\n")
    with pytest.raises(AffnerfError) as info:
        load_partnet_object(src, mapping=mapping)
    message = str(info.value)
    assert name in message and "\n" not in message


def test_not_a_folder(tmp_path: Path) -> None:
    with pytest.raises(AffnerfError, match="not a folder"):
        load_partnet_object(tmp_path / "nothing")
