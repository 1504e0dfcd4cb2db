"""Grasps in the photo's camera frame (affnerf.grasp.camera_frame): from the camera a prediction's fit found."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from affnerf.cli.main import main
from affnerf.data.cameras import look_at
from affnerf.grasp.camera_frame import fitted_camera_pose, object_to_camera, poses_in_camera
from affnerf.meshio import LabelledMesh, write_labelled_ply


def _prediction_folder(folder, c2w=None, fit=True):
    folder.mkdir(parents=True, exist_ok=True)
    box = trimesh.creation.box(extents=(0.04, 0.05, 0.12))
    labels = {"affordance": np.ones(len(box.faces), np.uint8)}
    write_labelled_ply(
        folder / "affordance_model.ply", LabelledMesh(np.asarray(box.vertices), box.faces, face_props=labels)
    )
    camera = {"c2w": (look_at(np.array([0.3, -0.4, 0.35]), np.zeros(3)) if c2w is None else c2w).tolist()}
    (folder / "prediction.json").write_text(json.dumps({"fit": {"camera": camera} if fit else None}))
    return folder / "affordance_model.ply"


def test_object_to_camera_puts_the_object_where_the_camera_saw_it_at_metric_size():
    c2w = look_at(np.array([0.3, -0.4, 0.35]), np.zeros(3))
    for factor in (0.5, 2.0):
        to_cam = object_to_camera(c2w, factor)
        origin = to_cam @ np.array([0.0, 0.0, 0.0, 1.0])
        # straight ahead (-z) at the canonical distance times the size factor
        np.testing.assert_allclose(origin[:3], [0.0, 0.0, -factor * np.linalg.norm(c2w[:3, 3])], atol=1e-9)
    pose = np.eye(4)
    pose[:3, 3] = [0.01, 0.02, 0.03]
    moved = poses_in_camera(pose[None], object_to_camera(c2w, 1.0))[0]
    np.testing.assert_allclose(c2w @ moved, pose, atol=1e-9)  # back to the object frame


def test_grasp_plan_beside_a_fitted_prediction_writes_camera_frame_poses(tmp_path):
    mesh = _prediction_folder(tmp_path / "pred")
    out = tmp_path / "g"
    assert main(["grasp", "--mesh", str(mesh), "--affordance", "grasp", "--num", "3", "--refine-steps", "2",
                 "--object-size", "0.24", "--out", str(out)]) == 0  # fmt: skip
    data = json.loads((out / "grasps.json").read_text())
    camera = data["camera"]
    assert camera["source"] == "prediction.json fit.camera" and len(camera["grasp_poses"]) == len(data["grasps"])
    factor = 1.0 / data["size"]["scale"]
    expected = object_to_camera(fitted_camera_pose(mesh), factor)
    np.testing.assert_allclose(camera["object_to_camera"], expected, atol=1e-5)
    for grasp, in_camera in zip(data["grasps"], camera["grasp_poses"], strict=True):
        np.testing.assert_allclose(in_camera, expected @ np.asarray(grasp["pose"]), atol=1e-5)
        assert in_camera[2][3] < 0  # in front of the camera


def test_without_a_fit_there_is_no_camera_and_a_bad_pose_is_one_line(tmp_path, capsys):
    mesh = _prediction_folder(tmp_path / "plain", fit=False)
    assert fitted_camera_pose(mesh) is None
    out = tmp_path / "g"
    assert main(["grasp", "--mesh", str(mesh), "--num", "2", "--refine-steps", "1", "--out", str(out)]) == 0
    assert json.loads((out / "grasps.json").read_text())["camera"] is None
    bad = _prediction_folder(tmp_path / "bad", c2w=np.full((4, 4), 2.0))
    capsys.readouterr()
    assert main(["grasp", "--mesh", str(bad), "--num", "2", "--out", str(tmp_path / "g2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "prediction.json" in err[0] and "fit.camera.c2w" in err[0]
    assert not (tmp_path / "g2" / "grasps.json").exists()


@pytest.mark.parametrize("content", ["[1, 2]", '{"fit": {"camera": {}}}'])
def test_other_prediction_files_have_no_camera(tmp_path, content):
    mesh = _prediction_folder(tmp_path / "p")
    (tmp_path / "p" / "prediction.json").write_text(content)
    assert fitted_camera_pose(mesh) is None
