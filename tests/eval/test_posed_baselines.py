"""``affnerf eval --method semantic-ray,gsnerf``: each baseline evaluated from a tiny run of its own kind with 3 posed
input views (labelled ``<name>-3v``), 2D and 3D metrics; a run of another kind is refused."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from affnerf.cli.main import main
from affnerf.eval.protocol import METRIC_KEYS


def _eval(run, data, out, method: str) -> int:
    args = ["eval", "--run", str(run), "--data", str(data), "--method", method, "--out", str(out)]
    small = ["--input-views", "3", "--target-views", "2", "--scale", "0.25", "--device", "cpu"]
    return main([*args, *small, "--mesh-resolution", "12", "--max-objects", "1", "--categories", "bottle"])


@pytest.mark.parametrize("kind", ["semantic-ray", "gsnerf"])
def test_a_posed_baseline_is_evaluated_from_a_run_of_its_kind(kind, train_dataset, tiny_train_config, tmp_path, capsys):
    from affnerf.train.trainer import train

    config = tiny_train_config(steps=2, checkpoint_every=2, input_views=3)
    config = replace(config, model=replace(config.model, kind=kind))
    train(config)
    out = tmp_path / "eval"
    assert _eval(config.out, train_dataset, out, kind) == 0
    m = json.loads((out / f"metrics_{kind}-3v.json").read_text())
    assert m["method"] == f"{kind}-3v" and list(m["categories"]) == ["bottle"]
    cat = m["categories"]["bottle"]
    assert set(METRIC_KEYS) <= set(cat) and cat["views"] == 2 and 0.0 <= cat["mIoU"] <= 1.0
    assert "fscore_1cm" in cat
    other = "gsnerf" if kind == "semantic-ray" else "semantic-ray"
    assert _eval(config.out, train_dataset, out, other) == 2
    assert f"method {other} needs a run of kind {other}, this run is of kind {kind}" in capsys.readouterr().err
