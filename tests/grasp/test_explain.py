"""No grasp found: the narrowest width against the opening, and what to change, on stderr and in grasps.json."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from affnerf.cli.main import main
from affnerf.grasp.explain import explain_no_grasps, narrowest_width
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.planner import PlanConfig, plan_grasps
from affnerf.grasp.refine import RefineConfig
from affnerf.grasp.target import GraspObject
from affnerf.meshio import LabelledMesh, write_labelled_ply
from affnerf.vocab import affordance_id


def _bottle() -> GraspObject:
    """A 0.12 m wide body labelled grasp, and a 0.03 m thick cap-like block on top labelled `pour`."""
    body = trimesh.creation.cylinder(radius=0.06, height=0.2, sections=48)
    neck = trimesh.creation.box(extents=(0.03, 0.03, 0.05))
    neck.apply_translation((0.0, 0.0, 0.125))
    labels = np.concatenate(
        [np.full(len(body.faces), affordance_id("grasp")), np.full(len(neck.faces), affordance_id("pour"))]
    )
    mesh = trimesh.util.concatenate([body, neck])
    return GraspObject(np.asarray(mesh.vertices), np.asarray(mesh.faces), labels, "bottle")


def test_narrowest_width_is_the_body_diameter():
    obj = _bottle()
    width = narrowest_width(obj, obj.face_affordance == affordance_id("grasp"), 0.5)
    assert width == pytest.approx(0.12, abs=0.004)


def test_wide_body_finds_no_grasp_and_says_why():
    obj = _bottle()
    config = PlanConfig(affordance="grasp", num=4, refine=RefineConfig(steps=0))
    assert plan_grasps(obj, config) == []
    why = explain_no_grasps(obj, config, ParallelJawGripper(), "category bottle")
    assert why["narrowest_width"] == pytest.approx(0.12, abs=0.004) and why["max_opening"] == 0.08
    assert "wider than the gripper's 0.080 m opening" in why["reason"]
    assert why["other_affordances"]["pour"] == pytest.approx(0.03, abs=0.002)
    assert why["advice"][0].startswith("--affordance pour")
    assert any("--max-opening" in a for a in why["advice"]) and any("--object-size" in a for a in why["advice"])
    # the advice works: a gripper wide enough finds grasps
    assert plan_grasps(obj, config, ParallelJawGripper(max_opening=why["narrowest_width"] + 0.01))


def test_cli_reports_no_grasp_on_stderr_and_in_grasps_json(tmp_path, capsys):
    obj = _bottle()
    mesh = tmp_path / "bottle.ply"
    props = {"affordance": obj.face_affordance.astype(np.uint8)}
    write_labelled_ply(mesh, LabelledMesh(obj.vertices, obj.faces, face_props=props))
    out = tmp_path / "g"
    args = ["grasp", "--mesh", str(mesh), "--out", str(out), "--affordance", "grasp", "--refine-steps", "0"]
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "no grasp found: the narrowest section of the 'grasp' surface is 0.1" in err and "--max-opening" in err
    data = json.loads((out / "grasps.json").read_text())
    assert data["grasps"] == [] and data["no_grasp"]["narrowest_width"] == pytest.approx(0.12, abs=0.004)
    assert main([*args, "--max-opening", "0.14"]) == 0
    assert "no grasp found" not in capsys.readouterr().err
    assert json.loads((out / "grasps.json").read_text())["grasps"]
