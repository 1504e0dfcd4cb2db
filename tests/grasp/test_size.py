"""Metric size of objects to grasp: dataset scale, the category table, --object-size, masses, and the CLI's
grasps.json in the metric frame."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from affnerf.cli.main import main
from affnerf.data.dataset import Dataset
from affnerf.errors import AffnerfError
from affnerf.grasp.size import (
    CATEGORY_SIZE,
    enclosed_volume,
    extent,
    object_mass,
    rescale_poses,
    resolve_size,
    scaled,
    size_for,
)
from affnerf.grasp.target import GraspObject, load_grasp_object
from affnerf.meshio import LabelledMesh, write_labelled_ply
from affnerf.objects.registry import make_object


def _write(path, mesh: trimesh.Trimesh, label: int = 1):
    props = {"affordance": np.full(len(mesh.faces), label, np.uint8)}
    write_labelled_ply(path, LabelledMesh(np.asarray(mesh.vertices, float), np.asarray(mesh.faces), face_props=props))
    return path


def test_dataset_scale_gives_real_screwdriver_lengths(train_dataset):
    ds = Dataset.open(train_dataset)
    entries = ds.objects(None, "screwdriver")
    assert entries
    for entry in entries:
        mesh = ds.load_object(entry).folder / "mesh.ply"
        canonical = load_grasp_object(mesh)
        size = resolve_size(mesh, canonical.vertices, None, None)
        assert size.source == "transforms.json scale"
        assert extent(canonical.vertices) == pytest.approx(0.44, abs=0.01)
        assert 0.15 <= extent(canonical.vertices) * size.factor <= 0.3


@pytest.mark.parametrize("category", sorted(CATEGORY_SIZE))
def test_procedural_scale_agrees_with_the_category_table(category):
    """The generator's metric sizes (source = canonical / scale) lie within a factor 2 of the typical size."""
    lengths = []
    for seed in range(4):
        asset = make_object(category, seed)
        lengths.append(float(np.ptp(asset.bounds(), axis=0).max()) / asset.scale)
    assert 0.5 < np.median(lengths) / CATEGORY_SIZE[category] < 2.0


def test_size_order_and_errors():
    assert size_for(0.44, object_size=0.2, scale=2.0, category="pen").factor == pytest.approx(0.2 / 0.44)
    assert size_for(0.44, scale=2.0, category="pen").source == "transforms.json scale"
    assert size_for(0.44, category="cabinet").factor == pytest.approx(0.8 / 0.44)
    assert size_for(0.44, category="unknown").factor == 1.0
    with pytest.raises(AffnerfError, match="--object-size"):
        size_for(0.44, object_size=-1.0)


def test_mass_is_volume_times_density_and_scaling_is_about_the_origin():
    box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    assert enclosed_volume(box.vertices, box.faces) == pytest.approx(0.006)
    assert object_mass(box.vertices, box.faces, "teapot") == pytest.approx(0.006 * 400.0)
    assert object_mass(box.vertices * 0.5, box.faces, None) == pytest.approx(0.006 / 8 * 700.0)
    obj = GraspObject(np.asarray(box.vertices), np.asarray(box.faces), None, "b")
    assert extent(scaled(obj, 0.5).vertices) == pytest.approx(0.15)
    poses = rescale_poses(np.tile(np.eye(4), (2, 1, 1)) + np.eye(4, k=3)[None], 2.0)
    assert poses[:, 0, 3].tolist() == [2.0, 2.0] and np.allclose(poses[:, :3, :3], np.eye(3))


def test_cli_plans_at_the_given_size_and_scores_in_any_frame(tmp_path, capsys):
    # canonical 0.44 m rod, 0.22 m thick: too wide for the gripper as given, 0.04 m thick at 0.08 m long
    mesh = _write(tmp_path / "rod.ply", trimesh.creation.box(extents=(0.22, 0.22, 0.44)))
    out = tmp_path / "g"
    args = ["grasp", "--mesh", str(mesh), "--out", str(out), "--num", "4", "--refine-steps", "2"]
    assert main([*args, "--object-size", "0.08"]) == 0
    assert "0.080 m (--object-size)" in capsys.readouterr().err
    data = json.loads((out / "grasps.json").read_text())
    assert data["frame"] == "metric" and data["size"]["scale"] == pytest.approx(0.44 / 0.08)
    assert data["size"]["largest_side"] == pytest.approx(0.08) and data["no_grasp"] is None
    contacts = np.array([g["contacts"] for g in data["grasps"]])
    assert len(contacts) == 4 and np.abs(contacts).max() <= 0.04 + 1e-6
    assert all(g["width"] == pytest.approx(0.04, abs=1e-3) for g in data["grasps"])
    best = data["grasps"][0]["epsilon"]
    for extra in ([], ["--object-size", "0.12"]):  # the file's scale, or another size: poses move with the mesh
        assert main(["grasp", "score", "--mesh", str(mesh), "--grasps", str(out / "grasps.json"), *extra]) == 0
        first = capsys.readouterr().out.splitlines()[2].split()
        if extra:  # epsilon is not scale-free: the pads' torsion and patch are in metres
            assert 0.0 < float(first[1]) != pytest.approx(best, rel=1e-3)
        else:
            assert float(first[1]) == pytest.approx(best, rel=1e-3)
        assert float(first[2]) == pytest.approx(0.04 * (1.5 if extra else 1), abs=1e-3)


def test_dataset_mesh_is_planned_at_its_metric_size(train_dataset, tmp_path, capsys):
    ds = Dataset.open(train_dataset)
    folder = ds.load_object(ds.objects(None, "screwdriver")[0]).folder
    scale = json.loads((folder / "transforms.json").read_text())["scale"]
    out = tmp_path / "g"
    code = main(["grasp", "--mesh", str(folder / "mesh.ply"), "--out", str(out), "--num", "3", "--refine-steps", "0"])
    assert code == 0
    data = json.loads((out / "grasps.json").read_text())
    assert data["size"]["scale"] == pytest.approx(scale) and data["size"]["source"] == "transforms.json scale"
    contacts = np.array([g["contacts"] for g in data["grasps"]]).reshape(-1, 3)
    assert np.abs(contacts).max() <= 0.22 / scale + 1e-6
