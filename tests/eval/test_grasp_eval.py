"""``affnerf eval grasp`` end to end on a tiny run: the true or predicted mesh × whole surface or task part, and the
true mesh restricted to the predicted task part; scores on the true mesh at metric size, Table 3; and the summary on
hand-built numbers."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from affnerf.cli.main import main
from affnerf.eval.grasp_table import CONDITIONS, LABELS, summarise, table3_markdown


def test_grasp_eval_writes_the_2x2_table3(trained_runs, train_dataset, tmp_path):
    out = tmp_path / "grasps"
    args = ["eval", "grasp", "--run", str(trained_runs["affnerf"]), "--data", str(train_dataset), "--out", str(out)]
    args += ["--categories", "screwdriver,bottle", "--max-objects", "1", "--num", "4"]
    args += ["--lift-grasps", "1", "--resolution", "32", "--level", "0.5", "--refine-steps", "2", "--device", "cpu"]
    # the encoder's codes: the fit (30 steps by default) and its camera search were a quarter of the time; the fit in
    # this evaluation: test_the_true_mesh_takes_the_predicted_fields_labels below, and predict/test_invert.py
    args += ["--fit-steps", "0"]
    assert main(args) == 0
    objects = json.loads((out / "grasp_objects.json").read_text())
    assert sorted(o["category"] for o in objects) == ["bottle", "screwdriver"]
    for o in objects:
        assert set(CONDITIONS) <= set(o) and o["task"] == "grasp"
        assert 0.1 < o["size"]["largest_side"] < 0.4 and o["mass"] > 0  # metric, not the canonical 0.44 m
        true_whole = o["true_whole"]
        assert true_whole["grasps"] > 0 and true_whole["no_grasp"] is None
        assert all(e >= 0 for e in true_whole["epsilon"]) and len(true_whole["lift"]) == 1
        assert len(true_whole["disturb"]) == 1 and (true_whole["lift"][0] or not true_whole["disturb"][0])
        assert len(true_whole["on_part"]) == true_whole["grasps"]
        part = o["true_part"]
        assert part["grasps"] == 0 or all(part["on_part"])  # planned on the true part, scored on it
        relabelled = o["true_predictedpart"]
        assert len(relabelled["on_part"]) == relabelled["grasps"] and len(relabelled["epsilon"]) == relabelled["grasps"]
        assert relabelled["grasps"] > 0 or relabelled["no_grasp"]
    metrics = json.loads((out / "grasp_metrics.json").read_text())
    assert set(metrics["mean"]) == set(CONDITIONS)
    assert metrics["categories"]["screwdriver"]["true_whole"]["epsilon_ratio"] == pytest.approx(1.0)
    machine = metrics["settings"]["machine"]  # what a rerun needs to give the same bits
    assert machine["threads_per_object"] == 1 and machine["packages"]["pybullet"] and machine["torch"]
    assert metrics["settings"]["workers"] == "2"
    table = (out / "table3.md").read_text()
    assert all(f"| {LABELS[c]} |" in table for c in CONDITIONS)
    assert "L1 grasp wrench space" in table and "μ = 0.5" in table and "soft-finger" in table
    assert "| | bottle | screwdriver | Average |" in table and "Physics lift success" in table
    assert "Lift-and-disturb success" in table
    for category in ("bottle", "screwdriver"):  # five panels: a title strip and three 200 px views each
        picture = np.asarray(Image.open(out / f"grasps_{category}.png"))
        assert picture.shape == (5 * (18 + 200), 600, 3) and picture.std() > 10
    # the default two workers each took one object; one worker taking both, one after the other, gives the same
    # numbers (each object on one thread, nothing carried from one object to the next)
    args[args.index(str(out))] = str(tmp_path / "one_worker")
    assert main([*args, "--workers", "1", "--no-pictures"]) == 0
    assert json.loads((tmp_path / "one_worker" / "grasp_objects.json").read_text()) == objects


def test_the_true_mesh_takes_the_predicted_fields_labels(trained_runs, train_dataset):
    from affnerf.data.dataset import Dataset
    from affnerf.eval.grasps import predict_object, with_predicted_labels
    from affnerf.grasp.target import GraspObject
    from affnerf.meshio import read_labelled_ply
    from affnerf.predict.loading import load_model
    from affnerf.predict.mesh import label_faces

    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects("train", ["screwdriver"])[0])
    true = GraspObject.from_mesh(read_labelled_ply(obj.folder / "mesh.ply"), "true")
    loaded = load_model(trained_runs["affnerf"], "cpu")
    prediction = predict_object(loaded, obj, 0, fit_steps=2)
    relabelled = with_predicted_labels(prediction, true)
    assert prediction.fitted and np.array_equal(relabelled.vertices, true.vertices)
    assert relabelled.face_affordance.shape == true.face_affordance.shape and relabelled.face_affordance.min() >= 1
    fitted = label_faces(true.vertices, true.faces, loaded.model.point_fields(prediction.encoding)[1])
    first = label_faces(true.vertices, true.faces, loaded.model.point_fields(prediction.first)[1])
    assert np.array_equal(relabelled.face_affordance, fitted)
    assert np.array_equal(relabelled.face_agrees, first == fitted)
    assert with_predicted_labels(prediction, true, agreement=False).face_agrees is None


def _cond(eps, on, lift):
    return {"grasps": len(eps), "epsilon": eps, "on_part": on, "lift": lift}


def test_summary_ratios_shares_and_objects_without_grasps():
    empty = _cond([], [], [])
    objects = [
        {
            "category": "cabinet",
            "true_whole": _cond([0.2, 0.4], [True, False], [True]),
            "true_part": _cond([0.15], [True], [False]),
            "true_predictedpart": _cond([0.3], [False], [True]),
            "predicted_whole": empty,
            "predicted_part": _cond([0.1], [False], [True]),
        },
        {
            "category": "cabinet",
            "true_whole": _cond([0.1], [True], [False]),
            "true_part": empty,
            "true_predictedpart": _cond([0.1], [True], [True]),
            "predicted_whole": _cond([0.2], [True], [True]),
            "predicted_part": _cond([0.05], [True], [True]),
        },
    ]
    s = summarise(objects)
    c = s["categories"]["cabinet"]
    assert c["true_whole"]["epsilon"] == pytest.approx((0.3 + 0.1) / 2)
    assert c["true_part"]["epsilon"] == pytest.approx(0.075)  # the object without grasps counts as 0
    assert c["true_part"]["epsilon_ratio"] == pytest.approx(0.075 / 0.2)
    assert c["predicted_part"]["epsilon_ratio"] == pytest.approx(0.075 / 0.1)
    assert c["true_whole"]["on_part_share"] == pytest.approx(2 / 3)
    assert c["true_whole"]["lift_success"] == 0.5 and c["predicted_whole"]["lift_success"] == 1.0
    assert c["true_part"]["disturb_success"] is None
    assert s["mean"]["true_part"]["epsilon_ratio"] == pytest.approx(0.075 / 0.2)
    assert c["true_predictedpart"]["epsilon_ratio"] == pytest.approx(0.2 / 0.2)  # against the true whole surface
    assert c["true_predictedpart"]["on_part_share"] == 0.5
    table = table3_markdown(s, {"split": "test"})
    assert "| True mesh, true task part | 0.0750 | 0.0750 |" in table
    assert "| True mesh, predicted task part | 0.2000 | 0.2000 |" in table
    ratio = f"{c['true_part']['epsilon_ratio']:.2f}"  # 0.375 give or take rounding
    assert (
        f"| True mesh, true task part | {ratio} | {ratio} |" in table
        and "| True mesh, whole surface | 1.00 | 1.00 |" in table
    )


def test_a_meshs_two_rows_average_over_the_same_categories():
    empty = _cond([], [], [])
    objects = [
        {  # the predicted part has no grasp on the cabinet: its shares are undefined there
            "category": "cabinet",
            "true_whole": _cond([0.1], [False], [False]),
            "true_part": _cond([0.1], [True], [False]),
            "true_predictedpart": _cond([0.1], [True], [False]),
            "predicted_whole": _cond([0.1], [False], [False]),
            "predicted_part": empty,
        },
        {
            "category": "pen",
            "true_whole": _cond([0.2], [True], [True]),
            "true_part": _cond([0.2], [True], [True]),
            "true_predictedpart": _cond([0.2], [True], [True]),
            "predicted_whole": _cond([0.2], [True], [True]),
            "predicted_part": _cond([0.2], [True], [True]),
        },
    ]
    s = summarise(objects)
    # the predicted whole surface's 0% on the cabinet would make it look worse than the part, which has no number
    assert s["mean"]["predicted_whole"]["lift_success"] == 1.0 and s["mean"]["predicted_part"]["lift_success"] == 1.0
    assert s["mean"]["predicted_whole"]["left_out"]["lift_success"] == ["cabinet"]
    assert s["mean"]["true_whole"]["lift_success"] == 0.5 and "lift_success" not in s["mean"]["true_whole"]["left_out"]
    assert s["mean"]["predicted_part"]["epsilon"] == pytest.approx(0.1)  # ε counts 0 for no grasp: every category
    assert s["categories"]["cabinet"]["predicted_part"]["no_grasp_objects"] == 1
    assert s["mean"]["predicted_part"]["no_grasp_objects"] == 1 and s["mean"]["predicted_part"]["objects"] == 2
    table = table3_markdown(s, {"split": "test"})
    assert "leave out the categories where one row of the same mesh has no grasp (predicted mesh: cabinet)" in table
    assert f"| {LABELS['predicted_part']} | 1/1 | 0/1 | 1/2 |" in table


def test_no_grasp_says_the_narrowest_width_against_the_opening():
    import trimesh

    from affnerf.eval.grasps import _plan
    from affnerf.grasp.gripper import ParallelJawGripper
    from affnerf.grasp.planner import PlanConfig
    from affnerf.grasp.refine import RefineConfig
    from affnerf.grasp.target import GraspObject
    from affnerf.vocab import affordance_id

    body = trimesh.creation.cylinder(radius=0.06, height=0.2, sections=48)  # 0.12 m across, wider than 0.08 m
    obj = GraspObject(body.vertices, body.faces, np.full(len(body.faces), affordance_id("grasp")), "bottle")
    config = PlanConfig(affordance="grasp", num=4, refine=RefineConfig(steps=0))
    grasps, why = _plan(obj, config, ParallelJawGripper(), "transforms.json scale")
    assert grasps == [] and why.startswith("no grasp found: the narrowest section of the 'grasp' surface is 0.1")
    assert "wider than the gripper's 0.080 m opening" in why


def test_predicted_models_keep_their_own_width_clearance_and_no_grasp_names_it(tmp_path):
    import trimesh

    from affnerf.eval.grasps import GraspEvalConfig, _plan, condition_settings
    from affnerf.grasp.gripper import ParallelJawGripper
    from affnerf.grasp.planner import WIDTH_CLEARANCE, PlanConfig
    from affnerf.grasp.refine import RefineConfig
    from affnerf.grasp.target import GraspObject
    from affnerf.vocab import affordance_id

    config = GraspEvalConfig(run=tmp_path, data=tmp_path, out=tmp_path, predicted_clearance=0.02)
    plan = PlanConfig(num=4, refine=RefineConfig(steps=0))
    predicted = condition_settings(plan, "predicted", "grasp", config)
    true = condition_settings(plan, "true", "none", config)
    assert (predicted.affordance, predicted.width_clearance) == ("grasp", 0.02)
    assert (true.affordance, true.width_clearance) == ("none", WIDTH_CLEARANCE)
    body = trimesh.creation.cylinder(radius=0.034, height=0.2, sections=48)  # 0.068 m across: fits 0.08 - 0.004 only
    obj = GraspObject(body.vertices, body.faces, np.full(len(body.faces), affordance_id("grasp")), "bottle")
    assert _plan(obj, true, ParallelJawGripper(), "transforms.json scale")[0]
    grasps, why = _plan(obj, predicted, ParallelJawGripper(), "transforms.json scale")
    assert grasps == [] and "0.080 m opening (less 0.02 m clearance)" in why


def test_no_workers_is_one_line_and_nothing_is_written(trained_runs, train_dataset, tmp_path, capsys):
    out = tmp_path / "grasps"
    args = ["eval", "grasp", "--run", str(trained_runs["affnerf"]), "--data", str(train_dataset), "--out", str(out)]
    assert main([*args, "--workers", "0"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == ["affnerf: error: --workers must be at least 1"]
    assert not out.exists()
