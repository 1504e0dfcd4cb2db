"""Every kind of bad input: one line naming the file and the problem, exit code 2, nothing already written
damaged; ``--debug`` shows the traceback instead."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from affnerf.cli.main import main


def _tree_digest(root: Path) -> dict[str, str]:
    return {
        p.relative_to(root).as_posix(): hashlib.sha1(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def _fails_cleanly(capsys, args: list[str], pattern: str) -> str:
    code = main(args)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    errors = [line for line in err if line.startswith("affnerf: error: ")]
    assert len(errors) == 1, err
    assert re.search(pattern, errors[0]), errors[0]
    return errors[0]


@pytest.fixture
def dataset_copy(train_dataset, tmp_path) -> Path:
    root = tmp_path / "ds"
    shutil.copytree(train_dataset, root)
    return root


def _train_args(data: Path, out: Path, *extra: str) -> list[str]:
    return [
        "train",
        "--data",
        str(data),
        "--out",
        str(out),
        "--config",
        "small",
        "--image-scale",
        "1.0",
        "--steps",
        "2",
        "--val-every",
        "0",
        "--no-progress",
        "--device",
        "cpu",
        "--model.encoder-width",
        "0.125",
        "--model.encoder-resolution",
        "32",
        "--model.field-width",
        "16",
        "--model.field-depth",
        "2",
        "--rays-per-step",
        "32",
        *extra,
    ]


def _first_train_object(root: Path) -> Path:
    entry = next(o for o in json.loads((root / "dataset.json").read_text())["objects"] if o["split"] == "train")
    return root / entry["path"]


@pytest.mark.parametrize(
    "damage, pattern",
    [
        ("corrupt_png", r"rgb/000\.png: cannot read image"),
        ("truncated_png", r"rgb/000\.png: cannot read image"),
        ("zero_bytes", r"rgb/000\.png: cannot read image"),
        ("missing_frame", r"rgb/000\.png: file not found"),
        ("mismatched_size", r"rgb/000\.png: image is 20x15, expected 40x30"),
        ("label_outside_vocabulary", r"affordance/000\.png: label id 200 is outside the 12 known ids"),
        ("label_wrong_size", r"affordance/000\.png: image is 7x7, expected 40x30"),
        ("nan_pose", r"transforms\.json: frame 0 transform_matrix has NaN or infinite entries"),
        ("non_rigid_pose", r"transforms\.json: frame 0 transform_matrix rotation is not rigid"),
        ("missing_pose", r"transforms\.json: frame 0 transform_matrix is missing"),
        ("other_format", r"dataset\.json: format is 'affnerf-0'"),
        ("empty_dataset", r"dataset\.json: no training objects"),
        ("unknown_category", r"dataset\.json: unknown category spoon"),
    ],
)
def test_training_on_bad_data(dataset_copy, tmp_path, capsys, damage, pattern):
    folder = _first_train_object(dataset_copy)
    transforms = folder / "transforms.json"
    extra: list[str] = []
    if damage == "corrupt_png":
        (folder / "rgb/000.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"\x00" * 40)
    elif damage == "truncated_png":
        data = (folder / "rgb/000.png").read_bytes()
        (folder / "rgb/000.png").write_bytes(data[: len(data) // 2])
    elif damage == "zero_bytes":
        (folder / "rgb/000.png").write_bytes(b"")
    elif damage == "missing_frame":
        (folder / "rgb/000.png").unlink()
    elif damage == "mismatched_size":
        Image.new("RGB", (20, 15)).save(folder / "rgb/000.png")
    elif damage == "label_outside_vocabulary":
        Image.fromarray(np.full((30, 40), 200, np.uint8)).save(folder / "affordance/000.png")
    elif damage == "label_wrong_size":
        Image.fromarray(np.zeros((7, 7), np.uint8)).save(folder / "affordance/000.png")
    elif damage in ("nan_pose", "non_rigid_pose", "missing_pose"):
        data = json.loads(transforms.read_text())
        frame = data["frames"][0]
        if damage == "nan_pose":
            frame["transform_matrix"][1][1] = float("nan")
        elif damage == "non_rigid_pose":
            frame["transform_matrix"][0][0] = 3.0
        else:
            del frame["transform_matrix"]
        transforms.write_text(json.dumps(data))
    elif damage == "other_format":
        index = json.loads((dataset_copy / "dataset.json").read_text())
        index["format"] = "affnerf-0"
        (dataset_copy / "dataset.json").write_text(json.dumps(index))
    elif damage == "empty_dataset":
        index = json.loads((dataset_copy / "dataset.json").read_text())
        index["objects"] = []
        (dataset_copy / "dataset.json").write_text(json.dumps(index))
    elif damage == "unknown_category":
        extra = ["--categories", "spoon"]
    before = _tree_digest(dataset_copy)
    _fails_cleanly(
        capsys, _train_args(dataset_copy, tmp_path / "run", "--cache-dir", str(tmp_path / "cache"), *extra), pattern
    )
    assert _tree_digest(dataset_copy) == before  # the dataset is untouched
    assert not (tmp_path / "run" / "checkpoints").exists()


@pytest.mark.parametrize("mode", ["P", "I;16", "RGBA", "L"])
def test_frames_of_other_image_modes_are_read(dataset_copy, tmp_path, mode):
    folder = _first_train_object(dataset_copy)
    rgb = Image.open(folder / "rgb/000.png")
    if mode == "I;16":
        grey = np.asarray(rgb.convert("L")).astype(np.uint16) * 257
        Image.fromarray(grey).save(folder / "rgb/000.png")
    else:
        rgb.convert(mode).save(folder / "rgb/000.png")
    assert main(_train_args(dataset_copy, tmp_path / "run", "--cache-dir", str(tmp_path / "cache"))) == 0


def test_debug_shows_the_traceback(dataset_copy, tmp_path):
    (_first_train_object(dataset_copy) / "rgb/000.png").write_bytes(b"")
    with pytest.raises(Exception, match="cannot read image"):
        main(_train_args(dataset_copy, tmp_path / "run", "--cache-dir", str(tmp_path / "cache"), "--debug"))


def test_checkpoint_of_another_class_count_is_refused(trained_runs, dataset_copy, tmp_path, capsys):
    index = json.loads((dataset_copy / "dataset.json").read_text())
    index["affordance_classes"] = index["affordance_classes"] + ["hang"]
    (dataset_copy / "dataset.json").write_text(json.dumps(index))
    for obj in index["objects"]:
        t = dataset_copy / obj["path"] / "transforms.json"
        data = json.loads(t.read_text())
        data["affordance_classes"] = index["affordance_classes"]
        t.write_text(json.dumps(data))
    run = tmp_path / "run"
    shutil.copytree(trained_runs["affnerf"], run)
    config = json.loads((run / "config.json").read_text())
    m = config["model"]
    args = [
        "train",
        "--config-file",
        str(run / "config.json"),
        "--data",
        str(dataset_copy),
        "--out",
        str(run),
        "--resume",
        "--steps",
        "40",
        "--cache-dir",
        str(tmp_path / "cache"),
    ]
    before = _tree_digest(run / "checkpoints")
    _fails_cleanly(capsys, args, r"step_00000030\.pt: checkpoint has 12 affordance classes, the dataset 13")
    assert _tree_digest(run / "checkpoints") == before
    assert m["kind"] == "affnerf"


def test_truncated_jpeg_and_zero_size_photo_for_predict(trained_runs, tmp_path, capsys):
    photo = tmp_path / "photo.jpg"
    Image.fromarray(np.full((60, 80, 3), 200, np.uint8)).save(photo, quality=90)
    photo.write_bytes(photo.read_bytes()[:200])
    args = ["predict", "--run", str(trained_runs["affnerf"]), "--out", str(tmp_path / "p"), "--device", "cpu"]
    _fails_cleanly(capsys, args + ["--image", str(photo)], r"photo\.jpg: cannot read image")
    empty = tmp_path / "empty.png"
    empty.write_bytes(b"")
    _fails_cleanly(capsys, args + ["--image", str(empty)], r"empty\.png: cannot read image")
    assert not (tmp_path / "p" / "prediction.json").exists()
