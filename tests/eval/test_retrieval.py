"""The retrieval baseline's bank: the dataset's train split, restricted to the run's training categories."""

from __future__ import annotations

import json
import shutil

from affnerf.cli.main import main


def test_a_dataset_without_training_objects_is_one_line_naming_the_bank(trained_runs, train_dataset, tmp_path, capsys):
    data = tmp_path / "ds"
    shutil.copytree(train_dataset, data)
    index = json.loads((data / "dataset.json").read_text())
    index["objects"] = [o for o in index["objects"] if o["split"] != "train"]  # e.g. imported test objects only
    (data / "dataset.json").write_text(json.dumps(index))
    args = [
        "eval",
        "--run",
        str(trained_runs["affnerf"]),
        "--data",
        str(data),
        "--split",
        "test",
        "--method",
        "retrieval",
        "--out",
        str(tmp_path / "eval"),
        "--target-views",
        "2",
        "--scale",
        "0.25",
        "--device",
        "cpu",
    ]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"affnerf: error: {data / 'dataset.json'}: the retrieval bank is empty")
    assert "train-split objects of the run's training categories" in err[0]
    assert not (tmp_path / "eval" / "metrics_retrieval.json").exists()
