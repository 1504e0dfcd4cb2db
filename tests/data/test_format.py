"""Round trips and validation of the dataset format (conventions §2)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from affnerf.data.cameras import Intrinsics
from affnerf.data.dataset import Dataset
from affnerf.data.format import FORMAT, check_pose, read_index, read_transforms
from affnerf.data.generate import camera_poses
from affnerf.data.raycast import FrameCaster
from affnerf.errors import AffnerfError
from affnerf.meshio import read_labelled_ply
from affnerf.objects.asset import merge_parts
from affnerf.objects.registry import make_object, object_seed
from affnerf.vocab import AFFORDANCE_CLASSES


def test_reader_returns_what_the_ray_caster_produced(tiny_dataset):
    ds = Dataset.open(tiny_dataset)
    entry = ds.objects(categories=["pen"])[1]
    obj = ds.load_object(entry)
    index = int(entry.id.rsplit("_", 1)[1])
    asset = make_object("pen", object_seed(3, "pen", index).spawn(2)[0])
    poses = camera_poses(3, "pen", index, 5)
    intr = Intrinsics.from_fov(64, 48, obj.record.intrinsics.camera_angle_x)
    caster = FrameCaster(merge_parts(asset))
    for i in range(len(obj)):
        expected = caster.cast_frame(intr, poses[i])
        np.testing.assert_array_equal(obj.pose(i), poses[i])
        np.testing.assert_array_equal(obj.rgb(i), expected.rgb)
        np.testing.assert_array_equal(obj.affordance(i), expected.affordance)
        np.testing.assert_array_equal(obj.part(i), expected.part)
        assert np.abs(obj.depth(i) - expected.depth).max() <= 0.0005 + 1e-6  # 1 mm steps


def test_transforms_hold_the_documented_keys(tiny_dataset):
    data = json.loads((tiny_dataset / "pen" / "pen_0000" / "transforms.json").read_text())
    for key in (
        "object_id",
        "category",
        "w",
        "h",
        "fl_x",
        "fl_y",
        "cx",
        "cy",
        "camera_angle_x",
        "background_color",
        "depth_unit_scale_factor",
        "affordance_classes",
        "parts",
        "frames",
    ):
        assert key in data
    assert data["affordance_classes"] == list(AFFORDANCE_CLASSES)
    assert data["depth_unit_scale_factor"] == 0.001
    assert {p["affordance"] for p in data["parts"]} <= {"grasp", "open", "write"}
    frame = data["frames"][0]
    assert frame["file_path"] == "rgb/000.png" and frame["part_file_path"] == "part/000.png"
    index = json.loads((tiny_dataset / "dataset.json").read_text())
    assert index["format"] == FORMAT
    assert {o["source"] for o in index["objects"]} == {"procedural"}


def test_mesh_ply_carries_part_ids_that_match_the_parts(tiny_dataset):
    record = read_transforms(tiny_dataset / "pen" / "pen_0000" / "transforms.json")
    mesh = read_labelled_ply(tiny_dataset / "pen" / "pen_0000" / "mesh.ply")
    ids = {p.id: p.affordance for p in record.parts}
    assert set(np.unique(mesh.face_props["part"]).tolist()) == set(ids)
    for pid, aff in ids.items():
        assert set(mesh.face_props["affordance"][mesh.face_props["part"] == pid].tolist()) == {
            AFFORDANCE_CLASSES.index(aff)
        }
    assert np.abs(mesh.vertices).max() <= 0.25


@pytest.mark.parametrize(
    "matrix, problem",
    [
        (None, "missing"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, 1]], "shape"),
        (np.where(np.eye(4) == 1, np.nan, 0.0).tolist(), "NaN"),
        ((np.eye(4) * [2, 1, 1, 1]).tolist(), "not rigid"),
        (np.diag([1.0, 1.0, -1.0, 1.0]).tolist(), "not rigid"),
    ],
)
def test_bad_poses_are_named(tmp_path, matrix, problem):
    with pytest.raises(AffnerfError, match=problem):
        check_pose(matrix, tmp_path / "transforms.json")


def test_bad_transforms_and_index_name_the_file(tiny_dataset, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(tiny_dataset, copy)
    path = copy / "pen" / "pen_0000" / "transforms.json"
    data = json.loads(path.read_text())
    data["frames"][2]["transform_matrix"][0][3] = float("inf")
    path.write_text(json.dumps(data))
    with pytest.raises(AffnerfError, match=r"transforms\.json: frame 2 transform_matrix has NaN or infinite"):
        read_transforms(path)
    index = json.loads((copy / "dataset.json").read_text())
    index["format"] = "affnerf-0"
    (copy / "dataset.json").write_text(json.dumps(index))
    with pytest.raises(AffnerfError, match=r"dataset\.json: format is 'affnerf-0'"):
        read_index(copy)
    (copy / "dataset.json").write_text("{not json")
    with pytest.raises(AffnerfError, match=r"dataset\.json: not valid JSON"):
        read_index(copy)


def test_reader_reports_missing_and_corrupt_frames(tiny_dataset, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(tiny_dataset, copy)
    obj = Dataset.open(copy).load_object("pen_0001")
    (obj.folder / "rgb" / "001.png").unlink()
    with pytest.raises(AffnerfError, match=r"rgb/001\.png: file not found"):
        obj.rgb(1)
    (obj.folder / "rgb" / "002.png").write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    with pytest.raises(AffnerfError, match=r"rgb/002\.png: cannot read image"):
        obj.rgb(2)
    with pytest.raises(AffnerfError, match="no object with id"):
        Dataset.open(copy).load_object("nope")
