"""``affnerf eval`` end to end on a tiny run and dataset, every method; ``affnerf metrics`` on label folders."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from PIL import Image

from affnerf.cli.main import main
from affnerf.data.dataset import Dataset
from affnerf.eval.methods import affnerf as conditioned_methods
from affnerf.eval.protocol import METRIC_KEYS
from affnerf.eval.runner import EvalConfig, build_method


def _eval(run, data, out, method, *extra):
    return main(
        [
            "eval",
            "--run",
            str(run),
            "--data",
            str(data),
            "--split",
            "test",
            "--method",
            method,
            "--out",
            str(out),
            "--target-views",
            "3",
            "--scale",
            "0.25",
            "--semantic-steps",
            "10",
            "--device",
            "cpu",
            "--mesh-resolution",
            "16",
            *extra,
        ]
    )


def test_every_method_gives_metrics_a_table_and_a_figure(trained_runs, train_dataset, tmp_path):
    out = tmp_path / "eval"
    assert _eval(trained_runs["affnerf"], train_dataset, out, "affnerf,retrieval,semantic-nerf,constant") == 0
    assert _eval(trained_runs["pixelnerf"], train_dataset, out, "pixelnerf", "--input-views", "3") == 0
    labels = {"affnerf", "retrieval", "semantic-nerf", "constant", "pixelnerf-3v"}
    for label in labels:
        m = json.loads((out / f"metrics_{label}.json").read_text())
        assert m["method"] == label and m["split"] == "test"
        assert set(m["categories"]) == {"bottle", "screwdriver"}
        for cat in m["categories"].values():
            assert set(METRIC_KEYS) <= set(cat) and cat["objects"] == 1 and cat["views"] == 3
            assert 0.0 <= cat["mIoU"] <= 1.0 and 0.0 <= cat["PA"] <= 1.0
        assert m["mean"]["objects"] == 2
        for block in [*m["categories"].values(), m["mean"]]:  # 3D metrics on by default; constant has no mesh
            if label == "constant":
                assert block["fscore_1cm"] is None and block["affordance_miou_3d"] is None
            else:
                assert 0.0 <= block["fscore_1cm"] <= 1.0 and 0.0 <= block["affordance_miou_3d"] <= 1.0
    assert json.loads((out / "metrics.json").read_text())["method"] == "affnerf"
    table = (out / "table2.md").read_text()
    for label in labels:
        assert f"| {label} |" in table
    assert "| mIoU | affnerf |" in table and "Average" in table
    figure = np.asarray(Image.open(out / "figure.png"))
    example = next((out / "examples" / "input").glob("*.png"))
    h, w = np.asarray(Image.open(example)).shape[:2]
    assert figure.shape[0] > 2 * h and figure.shape[1] >= 7 * w  # two objects; input | ground truth | five methods
    for label in labels:
        assert len(list((out / "examples" / label).glob("*.png"))) == 2
    constant = json.loads((out / "metrics_constant.json").read_text())
    assert constant["mean"]["PA_object"] == 0.0 and constant["mean"]["PSNR"] is None


def test_one_call_evaluates_every_method_with_its_own_run_and_views(trained_runs, train_dataset, tmp_path):
    out = tmp_path / "eval"
    runs = f"pixelnerf={trained_runs['pixelnerf']}"
    assert _eval(trained_runs["affnerf"], train_dataset, out, "affnerf,constant,pixelnerf-3v", "--runs", runs) == 0
    affnerf = json.loads((out / "metrics_affnerf.json").read_text())
    pixelnerf = json.loads((out / "metrics_pixelnerf-3v.json").read_text())
    assert affnerf["settings"]["input_views"] == "1" and pixelnerf["settings"]["input_views"] == "3"
    assert pixelnerf["settings"]["run"] == str(trained_runs["pixelnerf"])
    assert affnerf["settings"]["run"] == str(trained_runs["affnerf"])
    # the same numbers as the baseline evaluated on its own, with --run and --input-views 3
    alone = tmp_path / "alone"
    assert _eval(trained_runs["pixelnerf"], train_dataset, alone, "pixelnerf", "--input-views", "3") == 0
    by_itself = json.loads((alone / "metrics_pixelnerf-3v.json").read_text())
    assert pixelnerf["mean"]["mIoU"] == pytest.approx(by_itself["mean"]["mIoU"], abs=1e-6)
    table = (out / "table2.md").read_text()
    assert "| pixelnerf-3v |" in table and "| affnerf |" in table
    assert json.loads((out / "metrics.json").read_text())["method"] == "affnerf"


@pytest.mark.parametrize(
    ("method", "runs", "message"),
    [
        ("affnerf,pixelnerf-3v", "pixelnerf", "--runs 'pixelnerf': expected name=PATH"),
        ("affnerf", "nerfacto=x", "--runs 'nerfacto=x': unknown method 'nerfacto'"),
        ("affnerf", "pixelnerf=/no/such/run", "--runs 'pixelnerf=/no/such/run': /no/such/run: no such file"),
        ("affnerf,pixelnerf-3v", "PIX,pixelnerf=PIX", "--runs names pixelnerf twice"),
        ("affnerf,affnerf-1v", "", "evaluates affnerf twice"),
        ("affnerf,pixelnerf-0v", "", "at least 1 input view"),
        ("affnerf,pixelnerf-3v", "", "method pixelnerf needs a run of kind pixelnerf, this run is of kind affnerf"),
    ],
)
def test_bad_method_or_runs_lists_fail_before_anything_is_written(
    method, runs, message, trained_runs, train_dataset, tmp_path, capsys
):
    runs = runs.replace("PIX,", f"pixelnerf={trained_runs['pixelnerf']},").replace(
        "PIX", str(trained_runs["pixelnerf"])
    )
    out = tmp_path / "eval"
    assert _eval(trained_runs["affnerf"], train_dataset, out, method, "--runs", runs) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_wrong_run_for_a_method_is_a_clear_error(trained_runs, train_dataset, tmp_path, capsys):
    assert _eval(trained_runs["pixelnerf"], train_dataset, tmp_path / "e", "affnerf") == 2
    assert "method affnerf needs a run of kind affnerf, this run is of kind pixelnerf" in capsys.readouterr().err
    assert _eval(trained_runs["affnerf"], train_dataset, tmp_path / "e", "nerfacto") == 2
    assert "unknown method 'nerfacto'" in capsys.readouterr().err


def _labels(folder, name, array):
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.asarray(array, np.uint8)).save(path)


def test_metrics_scores_label_folders_per_category(tmp_path, capsys):
    gt, pred = tmp_path / "gt", tmp_path / "pred"
    _labels(gt, "a.png", [[0, 1], [1, 1]])
    _labels(pred, "a.png", [[0, 1], [0, 1]])
    _labels(gt, "b.png", [[0, 2], [2, 2]])
    _labels(pred, "b.png", [[0, 2], [2, 2]])
    assert main(["metrics", "--pred", str(pred), "--gt", str(gt), "--out", str(tmp_path / "m.json")]) == 0
    m = json.loads((tmp_path / "m.json").read_text())
    assert list(m["categories"]) == ["all"]
    assert m["categories"]["all"]["PA"] == pytest.approx(7 / 8)
    (tmp_path / "map.json").write_text(json.dumps({"a.png": "mug", "b": "pen"}))
    assert (
        main(
            [
                "metrics",
                "--pred",
                str(pred),
                "--gt",
                str(gt),
                "--category-map",
                str(tmp_path / "map.json"),
                "--out",
                str(tmp_path / "m2.json"),
            ]
        )
        == 0
    )
    m2 = json.loads((tmp_path / "m2.json").read_text())
    assert m2["categories"]["pen"]["mIoU"] == 1.0
    assert m2["categories"]["mug"]["mIoU"] == pytest.approx((1 / 2 + 2 / 3) / 2)
    assert m2["mean"]["mIoU"] == pytest.approx((1.0 + (1 / 2 + 2 / 3) / 2) / 2)
    assert "mug" in capsys.readouterr().out


def test_metrics_reports_a_missing_prediction(tmp_path, capsys):
    gt, pred = tmp_path / "gt", tmp_path / "pred"
    _labels(gt, "a.png", [[0, 1]])
    pred.mkdir()
    assert main(["metrics", "--pred", str(pred), "--gt", str(gt)]) == 2
    assert "a.png: prediction missing" in capsys.readouterr().err


def test_retrieval_bank_holds_only_the_categories_the_run_trained_on(trained_runs, train_dataset, monkeypatch):
    ds = Dataset.open(train_dataset)
    config = EvalConfig(run=trained_runs["affnerf"], data=train_dataset, out=train_dataset, device="cpu")
    every = build_method("retrieval", config, ds)
    assert {e.category for e in every.entries} == {"bottle", "screwdriver"}
    original = conditioned_methods.load_model

    def trained_on_bottles(path, device="cpu"):
        loaded = original(path, device)
        return replace(loaded, train_config={**loaded.train_config, "categories": "bottle"})

    monkeypatch.setattr(conditioned_methods, "load_model", trained_on_bottles)
    bottles = build_method("retrieval", config, ds)
    assert {e.category for e in bottles.entries} == {"bottle"}


def test_affnerf_fit_scores_the_fitted_codes(trained_runs, train_dataset, tmp_path):
    out = tmp_path / "eval"
    assert _eval(trained_runs["affnerf"], train_dataset, out, "affnerf,affnerf-fit", "--no-fast") == 0
    plain, fitted = (json.loads((out / f"metrics_{m}.json").read_text()) for m in ("affnerf", "affnerf-fit"))
    assert fitted["method"] == "affnerf-fit" and fitted["mean"]["objects"] == plain["mean"]["objects"] == 2
    assert 0.0 <= fitted["mean"]["mIoU"] <= 1.0 and fitted["mean"]["fscore_1cm"] is not None
    assert fitted["mean"]["PSNR"] != plain["mean"]["PSNR"]  # the fit changed what is rendered
    assert "| affnerf-fit |" in (out / "table2.md").read_text()
