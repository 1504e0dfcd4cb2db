"""``affnerf train-segmenter``: a short run writes a segmenter that predict can load; bad data is exit 2."""

from __future__ import annotations

import json

from affnerf.cli.main import main
from affnerf.model.segmenter import SegmenterConfig, load_segmenter


def test_a_short_run_writes_a_segmenter(train_dataset, tmp_path, capsys):
    out = tmp_path / "seg.pt"
    args = ["train-segmenter", "--data", str(train_dataset), "--out", str(out), "--steps", "2", "--batch", "2",
            "--pool", "4", "--val-photos", "2", "--network.base", "4", "--network.levels", "2",
            "--network.input-side", "32"]  # fmt: skip
    assert main(args) == 0
    summary = json.loads(capsys.readouterr().out.splitlines()[0])
    assert summary["steps"] == 2 and load_segmenter(out).config == SegmenterConfig(base=4, levels=2, input_side=32)


def test_a_missing_dataset_is_exit_2_naming_it(tmp_path, capsys):
    missing = tmp_path / "nowhere"
    assert main(["train-segmenter", "--data", str(missing), "--out", str(tmp_path / "s.pt")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "nowhere" in err and not (tmp_path / "s.pt").exists()
