"""``affnerf eval grasp`` end to end on a tiny run: both conditions, scores on the ground truth, Table 3."""

from __future__ import annotations

import json

from affnerf.cli.main import main
from affnerf.eval.grasps import summarise


def test_grasp_eval_writes_table3(trained_runs, train_dataset, tmp_path):
    out = tmp_path / "grasps"
    args = [
        "eval",
        "grasp",
        "--run",
        str(trained_runs["affnerf"]),
        "--data",
        str(train_dataset),
        "--out",
        str(out),
        "--categories",
        "screwdriver",
        "--num",
        "4",
        "--lift-grasps",
        "2",
        "--resolution",
        "32",
        "--level",
        "0.5",
        "--refine-steps",
        "2",
        "--device",
        "cpu",
    ]
    assert main(args) == 0
    objects = json.loads((out / "grasp_objects.json").read_text())
    assert {o["category"] for o in objects} == {"screwdriver"}
    for o in objects:
        original = o["original"]
        assert original["grasps"] > 0 and all(e >= 0 for e in original["epsilon"])
        assert len(original["on_grasp"]) == original["grasps"] and len(original["lift"]) <= 2
    metrics = json.loads((out / "grasp_metrics.json").read_text())
    assert set(metrics["mean"]) == {"original", "affordance"}
    table = (out / "table3.md").read_text()
    assert "| Original model (no affordance) |" in table and "| Affordance model |" in table
    assert "Physics lift success rate" in table


def test_summary_counts_objects_without_grasps_as_zero_quality():
    objects = [
        {
            "category": "pen",
            "original": {"grasps": 2, "epsilon": [0.2, 0.4], "on_grasp": [True, False], "lift": [True]},
            "affordance": {"grasps": 0, "epsilon": [], "on_grasp": [], "lift": []},
        },
        {
            "category": "pen",
            "original": {"grasps": 1, "epsilon": [0.1], "on_grasp": [True], "lift": [False]},
            "affordance": {"grasps": 1, "epsilon": [0.5], "on_grasp": [True], "lift": [True]},
        },
    ]
    s = summarise(objects)["categories"]["pen"]
    assert abs(s["original"]["epsilon"] - (0.3 + 0.1) / 2) < 1e-12
    assert abs(s["affordance"]["epsilon"] - 0.25) < 1e-12
    assert abs(s["original"]["on_grasp_share"] - 2 / 3) < 1e-12
    assert s["original"]["lift_success"] == 0.5 and s["affordance"]["lift_success"] == 1.0
