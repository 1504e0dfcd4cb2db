"""``affnerf eval calibrate``: the sweep's choice, the checkpoint it writes, and the level-from-grid meshing it uses
(conventions §5), on the tiny AFF-NeRF run and an analytic field."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import torch

from affnerf.cli.main import main
from affnerf.data.dataset import Dataset
from affnerf.eval import calibrate
from affnerf.eval.calibrate import CalibrateConfig, run_calibration
from affnerf.eval.calibration_choice import choose_level, choose_level_and_depth
from affnerf.metrics.surface import SurfaceSamples
from affnerf.predict.level import object_level
from affnerf.predict.loading import load_model, resolve_checkpoint
from affnerf.predict.mesh import evaluate_grid, extract_labelled_mesh, labelled_mesh_from_grid

FAST = ["--resolution", "16", "--device", "cpu", "--max-objects", "2"]


@pytest.fixture
def run(trained_runs, tmp_path):
    """A copy of the tiny AFF-NeRF run (calibration rewrites its checkpoint)."""
    return shutil.copytree(trained_runs["affnerf"], tmp_path / "run")


def _calibrate(run, data, *extra) -> dict:
    assert main(["eval", "calibrate", "--run", str(run), "--data", str(data), *FAST, *extra]) == 0
    return json.loads((run / "calibration.json").read_text())


def test_chosen_level_is_the_sweeps_best_and_is_stored(run, train_dataset, capsys):
    levels = ["7", "13", "300"]  # none is the current 50/m, so the stored level must change
    result = _calibrate(run, train_dataset, "--levels", *levels)
    rows = result["levels"]
    assert [r["level"] for r in rows] == [7.0, 13.0, 300.0]
    best = max(r["fscore_1cm"] for r in rows)
    swept = [sweep["level"] for sweep in result["optical_depths_by_level"]]
    assert swept[0] in [r["level"] for r in rows if r["fscore_1cm"] == best] and swept[0] == choose_level(rows, 50.0)
    assert len(swept) == 2 and result["chosen_level"] in swept
    by_level = {sweep["level"]: sweep["optical_depths"] for sweep in result["optical_depths_by_level"]}
    pair = (result["chosen_level"], result["chosen_optical_depth"])
    assert pair == choose_level_and_depth(by_level, 50.0)
    assert result["optical_depths"] == by_level[result["chosen_level"]]
    assert result["previous_level"] == 50.0 and result["split"] == "val" and result["resolution"] == 16
    assert len(result["objects"]) == 2 and result["stored"]
    for r in rows:
        assert 0.0 <= r["fscore_1cm"] <= 1.0 and 0 <= r["meshes_empty"] <= 2
    loaded = load_model(run, "cpu")
    assert loaded.model.config.surface_density == result["chosen_level"]
    assert loaded.path == resolve_checkpoint(run)
    out = capsys.readouterr().out.splitlines()
    depths = [r["optical_depth"] for r in result["optical_depths"]]
    assert depths == list(calibrate.DEFAULT_OPTICAL_DEPTHS)
    assert loaded.model.config.surface_optical_depth == result["chosen_optical_depth"]
    assert all(r["mean_level"] <= result["chosen_level"] for r in result["optical_depths"])
    assert len(out) == 3 + 2 * len(depths) + 1 and out[0].startswith("level 7/m: F@1cm")
    assert out[3].startswith(f"at {swept[0]:g}/m, optical depth 0:") and out[-1].startswith("chosen")


def test_dry_run_leaves_the_checkpoint_byte_identical(run, train_dataset):
    ckpt = resolve_checkpoint(run)
    before = ckpt.read_bytes()
    result = _calibrate(run, train_dataset, "--levels", "7", "300", "--dry-run")
    assert not result["stored"] and ckpt.read_bytes() == before


def test_a_checkpoint_file_is_calibrated_in_place(run, train_dataset, tmp_path):
    ckpt = shutil.copy(resolve_checkpoint(run), tmp_path / "model.pt")
    config = CalibrateConfig(
        data=train_dataset, checkpoint=ckpt, levels=(9.0,), max_objects=1, resolution=12, device="cpu"
    )
    result = run_calibration(config)
    assert result["chosen_level"] == 9.0 and load_model(ckpt).model.config.surface_density == 9.0
    assert json.loads((tmp_path / "model.calibration.json").read_text())["chosen_level"] == 9.0


@pytest.mark.parametrize(
    ("args", "message"),
    [(["--run", "nowhere"], "nowhere: no such run"), (["--split", "nosuch"], "no objects in split 'nosuch'")],
)
def test_bad_input_is_one_line_and_exit_2(run, train_dataset, capsys, args, message):
    argv = ["eval", "calibrate", "--data", str(train_dataset), *FAST, *args]
    if "--run" not in args:
        argv += ["--run", str(run)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err


def test_only_the_named_categories_choose_the_level(train_dataset):
    ds = Dataset.open(train_dataset)
    both = calibrate.calibration_objects(ds, "train", 10)
    bottles = calibrate.calibration_objects(ds, "train", 10, "bottle")
    assert {o.record.category for o in both} == {"screwdriver", "bottle"}
    assert bottles and {o.record.category for o in bottles} == {"bottle"}


def test_the_depths_are_swept_at_the_two_best_levels_and_the_best_pair_wins(run, train_dataset, monkeypatch):
    """Every object is a diffuse cone (peak 40/m) whose truth is the sphere its per-object level at optical depth 5
    cuts from base level 35/m (23/m). At depth 0 both levels miss it (F = 0) and the tie goes to 20/m, nearer the
    stored 10/m, where no depth helps (the per-object level only lowers the base): sweeping the depths at the best
    level only keeps F = 0. With both levels swept, (35/m, depth 5) finds the sphere."""

    def diffuse(points: torch.Tensor) -> torch.Tensor:
        return 40.0 * torch.clamp(1.0 - points.norm(dim=-1) / 0.2, min=0.0)

    resolution, half = 41, 0.25
    volume = evaluate_grid(diffuse, resolution, half)
    own = object_level(volume, 2 * half / (resolution - 1), 35.0, 5.0)
    assert 20.0 < own < 35.0 and object_level(volume, 2 * half / (resolution - 1), 20.0, 5.0) == 20.0
    calibrate.store_surface(resolve_checkpoint(run), 10.0, 0.0)
    monkeypatch.setattr(calibrate, "object_grid", lambda method, obj, inputs: (volume, _upper))
    monkeypatch.setattr(calibrate, "true_samples", lambda obj, seed: _sphere_samples(0.2 * (1.0 - own / 40.0)))
    config = CalibrateConfig(
        data=train_dataset, run=run, levels=(20.0, 35.0), optical_depths=(0.0, 5.0), resolution=resolution
    )
    result = run_calibration(config)
    assert [r["fscore_1cm"] for r in result["levels"]] == [0.0, 0.0]
    assert choose_level(result["levels"], 10.0) == 20.0  # the level a one-level depth sweep would have kept
    assert (result["chosen_level"], result["chosen_optical_depth"]) == (35.0, 5.0)
    assert result["optical_depths"][1]["fscore_1cm"] > 0.9
    assert load_model(run).model.config.surface_density == 35.0


def test_ties_go_to_miou_then_the_level_closest_to_the_current_one():
    rows = [
        {"level": 10.0, "fscore_1cm": 0.4, "affordance_miou_3d": 0.2},
        {"level": 35.0, "fscore_1cm": 0.4, "affordance_miou_3d": 0.2},
        {"level": 100.0, "fscore_1cm": 0.4, "affordance_miou_3d": 0.1},
    ]
    assert choose_level(rows, 50.0) == 35.0
    assert choose_level(rows, 5.0) == 10.0
    rows[2]["affordance_miou_3d"] = 0.3
    assert choose_level(rows, 50.0) == 100.0


def _cone(points: torch.Tensor) -> torch.Tensor:
    """Density 200/m at the centre falling linearly to 0 at radius 0.2 m: level L lies at r = 0.2 (1 - L/200)."""
    return 200.0 * torch.clamp(1.0 - points.norm(dim=-1) / 0.2, min=0.0)


def _upper(points: torch.Tensor) -> torch.Tensor:
    return (points[:, 2] > 0).long()


def test_levels_of_one_analytic_grid_lie_at_their_radii():
    volume = evaluate_grid(_cone, 41, 0.25)
    for level in (20.0, 50.0, 150.0):
        mesh = labelled_mesh_from_grid(volume, _upper, level, 0.25)
        radius = np.linalg.norm(mesh.vertices, axis=1)
        assert np.abs(radius - 0.2 * (1.0 - level / 200.0)).max() < 2e-3
        up = mesh.vertices[:, 2] > 0.01
        assert (mesh.vertex_props["affordance"][up] == 1).all()
        assert (mesh.vertex_props["affordance"][mesh.vertices[:, 2] < -0.01] == 0).all()
    assert len(labelled_mesh_from_grid(volume, _upper, 250.0, 0.25).faces) == 0  # never reached: empty
    same = extract_labelled_mesh(_cone, _upper, 41, 50.0, 0.25)
    assert np.array_equal(same.vertices, labelled_mesh_from_grid(volume, _upper, 50.0, 0.25).vertices)


def _sphere_samples(radius: float, count: int = 4000) -> SurfaceSamples:
    """Points on a sphere, labelled 1 above the equator and 0 below."""
    points = np.random.default_rng(0).normal(size=(count, 3))
    points = radius * points / np.linalg.norm(points, axis=1, keepdims=True)
    return SurfaceSamples(points, (points[:, 2] > 0).astype(np.int64))


def test_the_level_whose_surface_matches_the_truth_wins(run, train_dataset, monkeypatch):
    """Every object's field is the analytic cone and its truth a sphere of radius 0.1 m, which the cone's 100/m
    level reproduces: the sweep must find it, store it, and score the others (5 cm or more away) F = 0."""

    def cone_grid(method, obj, inputs):
        half = method.loaded.model.config.scene_half_extent
        return evaluate_grid(_cone, method.mesh_resolution, half), _upper

    monkeypatch.setattr(calibrate, "object_grid", cone_grid)
    monkeypatch.setattr(calibrate, "true_samples", lambda obj, seed: _sphere_samples(0.1))
    config = CalibrateConfig(data=train_dataset, run=run, levels=(20.0, 50.0, 100.0, 150.0), resolution=41)
    result = run_calibration(config)
    by_level = {r["level"]: r for r in result["levels"]}
    assert result["chosen_level"] == 100.0 and load_model(run).model.config.surface_density == 100.0
    assert by_level[100.0]["fscore_1cm"] > 0.9 and by_level[100.0]["affordance_miou_3d"] > 0.8
    assert by_level[100.0]["chamfer_l1"] < 5e-3 and by_level[100.0]["meshes_empty"] == 0
    assert all(by_level[level]["fscore_1cm"] == 0.0 for level in (20.0, 50.0, 150.0))


def test_the_optical_depth_sweep_finds_a_diffuse_objects_own_level(run, train_dataset, monkeypatch):
    """A diffuse field (a cone of peak 40/m) never reaches the only level, 100/m, so without the per-object level
    every mesh is empty; its truth is the sphere where the per-object level at optical depth 2 cuts the cone, so
    that depth must win and be stored."""

    def diffuse(points: torch.Tensor) -> torch.Tensor:
        return 40.0 * torch.clamp(1.0 - points.norm(dim=-1) / 0.2, min=0.0)

    resolution, half = 41, 0.25
    volume = evaluate_grid(diffuse, resolution, half)
    own = object_level(volume, 2 * half / (resolution - 1), 100.0, 2.0)
    radius = 0.2 * (1.0 - own / 40.0)
    monkeypatch.setattr(calibrate, "object_grid", lambda method, obj, inputs: (volume, _upper))
    monkeypatch.setattr(calibrate, "true_samples", lambda obj, seed: _sphere_samples(radius))
    config = CalibrateConfig(
        data=train_dataset, run=run, levels=(100.0,), optical_depths=(0.0, 2.0), resolution=resolution
    )
    result = run_calibration(config)
    off, on = result["optical_depths"]
    assert off["meshes_empty"] == 2 and off["fscore_1cm"] == 0.0 and off["mean_level"] == 100.0
    assert on["fscore_1cm"] > 0.9 and on["mean_level"] == pytest.approx(own) and own < 40.0
    stored = load_model(run).model.config
    assert result["chosen_optical_depth"] == 2.0 == stored.surface_optical_depth and stored.surface_density == 100.0
