"""``affnerf data ...`` end to end, and its one-line errors with exit code 2."""

from __future__ import annotations

import json
import shutil
import textwrap

import numpy as np
import pytest
from PIL import Image

from affnerf.cli.main import main
from affnerf.data.partnet import load_mapping, write_partnet_fixture
from affnerf.vocab import AFFORDANCE_CLASSES


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
    code = main(
        ["data", "import-partnet", str(src), "--out", str(out), "--views", "1", "--width", "16", "--height", "12"]
    )
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


def _help_text(capsys, *verb: str) -> str:
    with pytest.raises(SystemExit) as exit_info:
        main([*verb, "--help"])
    assert exit_info.value.code == 0
    return capsys.readouterr().out


def _mapping_example(help_text: str) -> str:
    """The YAML block of the help text: the indented lines after 'a minimal one (YAML):'."""
    after = help_text.split("a minimal one (YAML):", 1)[1].splitlines()
    block = after[: next(i for i, line in enumerate(after) if line.startswith("Affordances"))]
    return textwrap.dedent("\n".join(line for line in block if line.strip())) + "\n"


def test_a_model_cat_without_mapping_says_how_to_give_one_and_the_help_example_works(tmp_path, capsys):
    src = write_partnet_fixture(tmp_path / "mug", model_cat="Mug")
    out = tmp_path / "ds"
    args = ["data", "import-partnet", str(src), "--out", str(out), "--views", "1", "--width", "16", "--height", "12"]
    assert main(args) == 2
    line = _error_line(capsys)
    assert "meta.json: model_cat 'Mug' has no mapping (known: Bottle," in line
    assert line.endswith(
        "give one with --mapping FILE (a minimal file is shown by 'affnerf data import-partnet --help')"
    )
    help_text = _help_text(capsys, "data", "import-partnet")
    assert ", ".join(AFFORDANCE_CLASSES[1:]) in " ".join(help_text.split())
    example = tmp_path / "mapping.yaml"
    example.write_text(_mapping_example(help_text))
    entry = load_mapping(example)["Mug"]  # the example loads with the code that reads mapping files
    assert (entry.category, entry.default, entry.parts) == ("mug", "contain", {"handle": "grasp"})
    assert main([*args, "--mapping", str(example)]) == 0
    assert json.loads((out / "dataset.json").read_text())["objects"][0]["category"] == "mug"


def test_reimport_with_other_settings_exits_2_naming_overwrite_which_replaces(tmp_path, capsys):
    src = write_partnet_fixture(tmp_path / "toy")
    out = tmp_path / "ds"
    args = ["data", "import-partnet", str(src), "--out", str(out), "--width", "16", "--height", "12"]
    assert main([*args, "--views", "1"]) == 0
    capsys.readouterr()
    assert main([*args, "--views", "2"]) == 2
    line = _error_line(capsys)
    folder = out / "cabinet" / "cabinet_pmtoy"
    assert line == (
        f"affnerf: error: {folder / 'transforms.json'}: already imported with views=1, not 2; import with "
        "the same settings, pass --overwrite to replace it, or use another --out"
    )
    assert len(list((folder / "rgb").iterdir())) == 1
    assert main([*args, "--views", "2", "--overwrite"]) == 0
    assert len(list((folder / "rgb").iterdir())) == 2
