"""``affnerf eval`` with the 3D metrics and view stability, end to end on the tiny runs and dataset."""

from __future__ import annotations

import json
import math

import pytest

from affnerf.cli.main import main
from affnerf.data.dataset import Dataset
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.metrics.surface import SURFACE_KEYS

FAST = ["--target-views", "2", "--scale", "0.25", "--mesh-resolution", "16", "--device", "cpu", "--split", "test"]


def _eval(run, data, out, method, *extra) -> dict[str, dict]:
    args = ["eval", "--run", str(run), "--data", str(data), "--method", method, "--out", str(out), *FAST, *extra]
    assert main(args) == 0
    return {p.stem.removeprefix("metrics_"): json.loads(p.read_text()) for p in out.glob("metrics_*.json")}


def _in_unit(value) -> bool:
    return value is not None and 0.0 <= value <= 1.0


def _check_measured(block: dict) -> None:
    assert _in_unit(block["fscore_1cm"]) and _in_unit(block["affordance_miou_3d"])
    assert block["chamfer_l1"] is None or 0.0 <= block["chamfer_l1"] < 1.0


def test_3d_metrics_per_method_and_category(trained_runs, train_dataset, tmp_path):
    out = tmp_path / "eval"
    results = _eval(trained_runs["affnerf"], train_dataset, out, "affnerf,retrieval,constant")
    for label in ("affnerf", "retrieval"):
        m = results[label]
        assert set(m["categories"]) == {"bottle", "screwdriver"}
        for block in [*m["categories"].values(), m["mean"]]:
            _check_measured(block)
        for cat in m["categories"].values():
            assert cat["meshes_empty"] in (0, 1)  # one test object per category
    retrieval = results["retrieval"]
    for block in [*retrieval["categories"].values(), retrieval["mean"]]:  # true training meshes: never empty
        assert block["meshes_empty"] == 0 and 0.0 < block["chamfer_l1"] < 0.2
    cats = retrieval["categories"]
    assert retrieval["mean"]["fscore_1cm"] == pytest.approx(
        (cats["bottle"]["fscore_1cm"] + cats["screwdriver"]["fscore_1cm"]) / 2
    )
    constant = results["constant"]  # no meshes: null, not zeros
    for block in [*constant["categories"].values(), constant["mean"]]:
        assert all(block[key] is None for key in (*SURFACE_KEYS, "meshes_empty"))
    assert results["affnerf"]["settings"]["mesh_resolution"] == "16"
    table = (out / "table2.md").read_text()
    assert "3D (conventions §5)" in table and "| chamfer_l1 | affnerf |" in table
    assert "| fscore_1cm | affnerf |" in table and "| affordance_miou_3d | affnerf |" in table
    assert "View stability" not in table and "stability" not in results["affnerf"]


def test_no_metrics_3d_gives_the_2d_only_run(trained_runs, train_dataset, tmp_path):
    out = tmp_path / "eval"
    m = _eval(trained_runs["affnerf"], train_dataset, out, "affnerf", "--no-metrics-3d")["affnerf"]
    for block in [*m["categories"].values(), m["mean"]]:
        assert not set(SURFACE_KEYS) & set(block) and 0.0 <= block["mIoU"] <= 1.0
    assert "3D (conventions §5)" not in (out / "table2.md").read_text()


def test_view_stability_reports_spreads_over_the_same_input_sets(trained_runs, train_dataset, tmp_path):
    plain = _eval(trained_runs["affnerf"], train_dataset, tmp_path / "plain", "retrieval")["retrieval"]
    out = tmp_path / "stable"
    results = _eval(trained_runs["affnerf"], train_dataset, out, "retrieval,constant", "--stability-views", "4")
    retrieval, constant = results["retrieval"], results["constant"]
    for key in ("mIoU", "PA", *SURFACE_KEYS):  # the extra input views do not enter the other metrics
        assert retrieval["mean"][key] == pytest.approx(plain["mean"][key])
    ds = Dataset.open(train_dataset)
    stability = retrieval["stability"]
    assert stability["views"] == 4 and len(stability["objects"]) == 2
    for oid, o in stability["objects"].items():
        obj = ds.load_object(next(e for e in ds.objects("test") if e.id == oid))
        inputs, targets = choose_views(len(obj), oid, ProtocolConfig(target_views=2))
        assert o["inputs"][0] == inputs and len({tuple(s) for s in o["inputs"]}) == 4
        assert not {v for s in o["inputs"] for v in s} & set(targets)
        assert len(o["mIoU"]) == len(o["fscore_1cm"]) == 4 and all(_in_unit(f) for f in o["fscore_1cm"])
        assert o["mIoU_spread"] == pytest.approx(max(o["mIoU"]) - min(o["mIoU"]))
        assert o["fscore_1cm_spread"] == pytest.approx(max(o["fscore_1cm"]) - min(o["fscore_1cm"]))
        assert stability["objects"][oid]["inputs"] == constant["stability"]["objects"][oid]["inputs"]
    for block in [*stability["categories"].values(), stability["mean"]]:
        assert _in_unit(block["mIoU_spread"]) and _in_unit(block["fscore_1cm_spread"])
    assert stability["mean"]["objects"] == 2
    for block in [*constant["stability"]["categories"].values(), constant["stability"]["mean"]]:
        assert block["mIoU_spread"] == 0.0 and block["fscore_1cm_spread"] is None  # same guess from every view
    table = (out / "table2.md").read_text()
    assert "View stability (4 input views per object)" in table and "| mIoU_spread | constant |" in table
    assert "| fscore_1cm_spread | constant | – | – | – |" in table  # rows: methods by name


def test_view_stability_of_an_image_conditioned_model(trained_runs, train_dataset, tmp_path):
    m = _eval(
        trained_runs["pixelnerf"], train_dataset, tmp_path, "pixelnerf", "--input-views", "3", "--stability-views", "2"
    )
    stability = m["pixelnerf-3v"]["stability"]
    for o in stability["objects"].values():
        assert [len(s) for s in o["inputs"]] == [3, 3] and not set(o["inputs"][0]) & set(o["inputs"][1])
        assert all(_in_unit(v) for v in o["mIoU"] + o["fscore_1cm"])
    assert math.isfinite(stability["mean"]["mIoU_spread"])


def test_stability_needs_enough_views_and_at_least_two_sets(trained_runs, train_dataset, tmp_path, capsys):
    base = ["eval", "--run", str(trained_runs["affnerf"]), "--data", str(train_dataset), "--method", "constant"]
    assert main([*base, "--out", str(tmp_path), *FAST, "--stability-views", "1"]) == 2
    assert "--stability-views is 0 (off) or at least 2" in capsys.readouterr().err
    assert main([*base, "--out", str(tmp_path), *FAST, "--stability-views", "7"]) == 2  # 7 + 2 > 8 views
    assert "has fewer than 9 views" in capsys.readouterr().err
