"""``affnerf data ...`` end to end, and its one-line errors with exit code 2."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from PIL import Image

from affnerf.cli.main import main
from affnerf.data.partnet import write_partnet_fixture


def _error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("affnerf: error: ")
    return err[0]


def test_generate_index_preview_stats(tmp_path, capsys):
    out = tmp_path / "ds"
    args = ["data", "generate", "--out", str(out), "--categories", "screwdriver", "--objects-per-category", "3"]
    assert main(args + ["--views", "3", "--width", "48", "--height", "36", "--workers", "2"]) == 0
    assert "3 objects made" in capsys.readouterr().out
    (out / "dataset.json").unlink()
    assert main(["data", "index", str(out)]) == 0
    assert len(json.loads((out / "dataset.json").read_text())["objects"]) == 3
    assert main(["data", "preview", str(out), "--out", str(tmp_path / "sheet.png"), "--views", "2"]) == 0
    sheet = np.asarray(Image.open(tmp_path / "sheet.png"))
    assert sheet.shape[0] > 100 and sheet.std() > 10
    assert main(["data", "stats", str(out), "--json-out", str(tmp_path / "stats.json")]) == 0
    text = capsys.readouterr().out
    assert "screwdriver" in text and "grasp" in text
    share = json.loads((tmp_path / "stats.json").read_text())["pixel_share_object"]
    assert share["grasp"] > 0 and share["screw"] > 0 and abs(sum(share.values()) - 1) < 1e-4


def test_unknown_category_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["data", "generate", "--out", str(tmp_path / "x"), "--categories", "spoon"]) == 2
    assert "unknown category 'spoon'" in _error_line(capsys)
    assert not (tmp_path / "x").exists()


def test_debug_shows_the_traceback(tmp_path):
    with pytest.raises(Exception, match="unknown category"):
        main(["data", "generate", "--out", str(tmp_path / "x"), "--categories", "spoon", "--debug"])


@pytest.mark.parametrize(
    "damage, expected",
    [
        ("missing_obj", r"original-\d+\.obj: file not found"),
        ("nonfinite", r"\.obj: .*non-finite"),
        ("bad_urdf", r"mobility\.urdf: .*XML"),
        ("unknown_category", r"meta\.json: model_cat 'Spoon' has no mapping"),
    ],
)
def test_import_bad_input_names_the_file_and_writes_nothing(tmp_path, capsys, damage, expected):
    src = write_partnet_fixture(
        tmp_path / "toy", missing_obj=damage == "missing_obj", nonfinite_vertex=damage == "nonfinite"
    )
    if damage == "bad_urdf":
        (src / "mobility.urdf").write_text("<robot><link name='base'>")
    if damage == "unknown_category":
        meta = json.loads((src / "meta.json").read_text())
        meta["model_cat"] = "Spoon"
        (src / "meta.json").write_text(json.dumps(meta))
    out = tmp_path / "ds"
    code = main(["data", "import-partnet", str(src), "--out", str(out), "--views", "1", "--width", "16", "--height", "12"])
    assert code == 2
    line = _error_line(capsys)
    import re

    assert re.search(expected, line), line
    assert not out.exists()


def test_import_keeps_an_existing_dataset_intact_on_error(tmp_path, capsys, tiny_dataset):
    out = tmp_path / "ds"
    shutil.copytree(tiny_dataset, out)
    before = (out / "dataset.json").read_bytes()
    good = write_partnet_fixture(tmp_path / "good")
    bad = write_partnet_fixture(tmp_path / "bad", missing_obj=True)
    assert main(["data", "import-partnet", str(good), str(bad), "--out", str(out), "--views", "1"]) == 2
    _error_line(capsys)
    assert (out / "dataset.json").read_bytes() == before
    assert not (out / "cabinet").exists()
