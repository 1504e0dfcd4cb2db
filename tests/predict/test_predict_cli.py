"""``affnerf predict`` end to end on a tiny trained run."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from PIL import Image

from affnerf.cli.main import main
from affnerf.data.dataset import Dataset
from affnerf.meshio import read_labelled_ply
from affnerf.predict.loading import resolve_checkpoint


@pytest.fixture(scope="module")
def photo(train_dataset, tmp_path_factory):
    """A test-split view of the tiny dataset saved as a photo, in several modes and sizes."""
    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects(split="test")[0])
    rgb = obj.rgb(0)
    folder = tmp_path_factory.mktemp("photos")
    big = Image.fromarray(rgb).resize((rgb.shape[1] * 5, rgb.shape[0] * 5), Image.NEAREST)
    paths = {
        "rgb": folder / "rgb.png",
        "grey": folder / "grey.png",
        "rgba": folder / "rgba.png",
        "jpg": folder / "big.jpg",
    }
    big.save(paths["rgb"])
    big.convert("L").save(paths["grey"])
    alpha = Image.fromarray(((obj.affordance(0) > 0) * 255).astype(np.uint8)).resize(big.size, Image.NEAREST)
    rgba = big.copy()
    rgba.putalpha(alpha)
    rgba.save(paths["rgba"])
    big.save(paths["jpg"], quality=90)
    return paths


@pytest.mark.parametrize("kind", ["rgb", "grey", "rgba", "jpg"])
def test_predict_writes_every_output(trained_runs, photo, tmp_path, capsys, kind):
    out = tmp_path / "pred"
    args = ["predict", "--run", str(trained_runs["affnerf"]), "--image", str(photo[kind]), "--out", str(out),
            "--views", "3", "--width", "32", "--height", "24", "--resolution", "24", "--level", "0.5",
            "--device", "cpu", "--grid-threshold", "0.1"]  # fmt: skip
    assert main(args) == 0
    summary = json.loads((out / "prediction.json").read_text())
    for name in summary["files"]:
        assert (out / name).is_file(), name
    assert {"input.png", "turntable.gif", "turntable/000.png", "prediction.json"} <= set(summary["files"])
    gif = Image.open(out / "turntable.gif")
    durations = []
    for i in range(gif.n_frames):  # identical neighbouring frames are merged: their durations add up
        gif.seek(i)
        durations.append(gif.info["duration"])
    assert sum(durations) == 3 * 120
    assert np.asarray(Image.open(out / "turntable/000.png")).shape == (24, 64, 3)  # RGB | overlay
    assert summary["object_separated_by"] == ("alpha" if kind == "rgba" else "uniform background")
    mesh = read_labelled_ply(out / "affordance_model.ply")
    assert len(mesh.faces) > 0 and "affordance" in mesh.vertex_props and mesh.vertex_colors is not None
    confirmed = mesh.face_props["confirmed"]  # fitted (the default): where the encoders' codes agree
    assert confirmed.shape == (len(mesh.faces),) and set(np.unique(confirmed)) <= {0, 1}
    assert set(summary["surface_area_m2"]) == set(summary["classes_present"]) and summary["classes_present"]
    assert (out / "affordance_model.glb").stat().st_size > 0
    fit = summary["fit"]  # test-time inversion is on by default
    assert fit["steps"] == 30
    assert set(fit["camera"]) == {"azimuth_deg", "elevation_deg", "distance_m", "c2w", "crop_fov_deg"}
    c2w, camera = np.asarray(fit["camera"]["c2w"]), fit["camera"]
    assert np.isclose(np.linalg.norm(c2w[:3, 3]), camera["distance_m"], atol=1e-4)  # at that distance,
    assert np.dot(c2w[:3, 2], c2w[:3, 3]) > 0.99 * camera["distance_m"]  # looking at the origin
    assert 0.0 < camera["crop_fov_deg"] < 60.0
    assert 0.0 <= fit["silhouette_iou"] <= 1.0 and fit["loss_after"] >= 0.0


def test_fit_steps_zero_keeps_the_encoders_codes(trained_runs, photo, tmp_path):
    common = ["predict", "--run", str(trained_runs["affnerf"]), "--image", str(photo["rgb"]), "--views", "1",
              "--width", "32", "--height", "24", "--resolution", "16", "--level", "0.5", "--device", "cpu",
              "--grid-threshold", "0.1"]  # fmt: skip
    assert main([*common, "--out", str(tmp_path / "plain"), "--fit-steps", "0"]) == 0
    assert main([*common, "--out", str(tmp_path / "fit"), "--fit-steps", "5"]) == 0
    plain = json.loads((tmp_path / "plain" / "prediction.json").read_text())
    fitted = json.loads((tmp_path / "fit" / "prediction.json").read_text())
    assert plain["fit"] is None and fitted["fit"]["steps"] == 5
    frames = [np.asarray(Image.open(tmp_path / name / "turntable/000.png")) for name in ("plain", "fit")]
    assert not np.array_equal(frames[0], frames[1])  # the fitted codes render another object
    check = np.asarray(Image.open(tmp_path / "fit" / "fit.png"))  # crop | render at the camera found | labels
    assert check.shape == (128, 3 * 128, 3) and "fit.png" in fitted["files"]
    assert "fit.png" not in plain["files"] and not (tmp_path / "plain" / "fit.png").exists()
    assert main([*common, "--out", str(tmp_path / "fit"), "--fit-steps", "0"]) == 0  # the stale check goes
    assert not (tmp_path / "fit" / "fit.png").exists()


def test_blank_and_missing_images_are_one_line_errors_and_keep_earlier_outputs(trained_runs, photo, tmp_path, capsys):
    out = tmp_path / "pred"
    base = ["predict", "--run", str(trained_runs["affnerf"]), "--out", str(out), "--views", "2", "--width", "16",
            "--height", "12", "--resolution", "16", "--device", "cpu"]  # fmt: skip
    assert main(base + ["--image", str(photo["rgb"])]) == 0
    before = (out / "prediction.json").read_bytes()
    capsys.readouterr()
    blank = tmp_path / "blank.png"
    Image.new("RGB", (50, 40), (255, 255, 255)).save(blank)
    assert main(base + ["--image", str(blank)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "blank.png: no object found" in err
    assert main(base + ["--image", str(tmp_path / "missing.png")]) == 2
    assert "missing.png: file not found" in capsys.readouterr().err
    assert (out / "prediction.json").read_bytes() == before
    assert not [p for p in out.iterdir() if p.name.startswith(".predict-")]


def test_a_pixelnerf_run_cannot_predict_from_a_photo(trained_runs, photo, tmp_path, capsys):
    args = [
        "predict",
        "--run",
        str(trained_runs["pixelnerf"]),
        "--image",
        str(photo["rgb"]),
        "--out",
        str(tmp_path / "x"),
    ]
    assert main(args) == 2
    assert "needs the input camera's pose" in capsys.readouterr().err


def test_a_folder_as_image_says_it_is_a_directory(trained_runs, tmp_path, capsys):
    folder = tmp_path / "photos"
    folder.mkdir()
    args = ["predict", "--run", str(trained_runs["affnerf"]), "--image", str(folder), "--out", str(tmp_path / "p"),
            "--device", "cpu"]  # fmt: skip
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"affnerf: error: {folder}: is a directory, not an image; give one image file (PNG, JPEG, ...)"
    assert not (tmp_path / "p" / "prediction.json").exists()


def _small(run, image, out) -> list[str]:
    return ["predict", "--run", str(run), "--image", str(image), "--out", str(out), "--views", "2", "--width", "16",
            "--height", "12", "--resolution", "16", "--device", "cpu"]  # fmt: skip


def _warnings(err: str) -> list[str]:
    return [line for line in err.strip().splitlines() if line.startswith("affnerf: warning: ")]


@pytest.mark.parametrize("kind", ["noise", "gradient"])
def test_no_separable_object_warns_once_and_records_the_separation(trained_runs, tmp_path, capsys, kind):
    if kind == "noise":
        rgb = np.random.default_rng(0).integers(0, 256, (60, 80, 3)).astype(np.uint8)
    else:
        rgb = np.broadcast_to(np.linspace(0, 255, 80)[None, :, None], (60, 80, 3)).round().astype(np.uint8)
    image = tmp_path / f"{kind}.png"
    Image.fromarray(rgb).save(image)
    out = tmp_path / "pred"
    assert main(_small(trained_runs["affnerf"], image, out)) == 0  # a warning, not an error: outputs are written
    # one line on the separation (the tiny model may add one that it predicts no surface at the default level)
    (warning,) = [w for w in _warnings(capsys.readouterr().err) if "separated" in w]
    assert warning.startswith(f"affnerf: warning: {image}: the object could not be separated with confidence (")
    assert "give the object's mask with --mask FILE" in warning
    separation = json.loads((out / "prediction.json").read_text())["separation"]
    assert separation["source"] == "uniform background" and separation["confident"] is False
    assert separation["background_uniformity"] < 0.5 and separation["problems"]
    if separation["note"] is not None:  # auto ran the salient model and GrabCut first (with the optional extra)
        assert separation["note"].startswith("neither the salient model nor GrabCut found an object")


def test_a_clean_photo_records_a_confident_separation_without_warning(trained_runs, photo, tmp_path, capsys):
    args = _small(trained_runs["affnerf"], photo["rgb"], tmp_path / "pred")
    assert main([*args, "--level", "0.5", "--grid-threshold", "0.1"]) == 0
    assert not _warnings(capsys.readouterr().err)
    separation = json.loads((tmp_path / "pred" / "prediction.json").read_text())["separation"]
    assert separation["confident"] is True and separation["problems"] == []
    assert 0.0 < separation["object_fraction"] < 0.9 and separation["background_uniformity"] == 1.0


def _empty_model(run, path):
    """The run's checkpoint with its density head turned off: zero weights, bias -100 (softplus ~ 0 everywhere)."""
    data = torch.load(resolve_checkpoint(run), map_location="cpu", weights_only=True)
    heads = [k for k in data["model"] if k.endswith("density.bias")]
    assert heads
    for bias in heads:
        data["model"][bias].fill_(-100.0)
        data["model"][bias.removesuffix("bias") + "weight"].zero_()
    torch.save(data, path)
    return path


def test_a_model_without_surface_writes_no_mesh_says_so_and_keeps_the_other_outputs(
    trained_runs, photo, tmp_path, capsys
):
    out = tmp_path / "pred"
    assert main([*_small(trained_runs["affnerf"], photo["rgb"], out), "--level", "0.5", "--grid-threshold", "0.1"]) == 0
    assert (out / "affordance_model.ply").is_file()  # an earlier prediction with a mesh
    capsys.readouterr()
    empty = _empty_model(trained_runs["affnerf"], tmp_path / "empty.pt")
    assert main(_small(empty, photo["rgb"], out)) == 0
    (warning,) = _warnings(capsys.readouterr().err)
    assert warning.startswith(f"affnerf: warning: {empty}: for {photo['rgb']}, the model predicts no surface: ")
    assert warning.endswith("so no mesh was written; lower --level or use a better-trained run")
    summary = json.loads((out / "prediction.json").read_text())
    assert summary["mesh"] is None and summary["mesh_note"].startswith("the model predicts no surface")
    assert summary["classes_present"] == [] and summary["surface_area_m2"] == {}
    assert not (out / "affordance_model.ply").exists() and not (out / "affordance_model.glb").exists()  # none stale
    assert set(summary["files"]) == {"input.png", "mask.png", "fit.png", "turntable/000.png", "turntable/001.png",
                                     "turntable.gif", "prediction.json"}  # fmt: skip
    for name in summary["files"]:
        assert (out / name).is_file(), name


def _tiny_args(trained_runs, out):
    return ["predict", "--run", str(trained_runs["affnerf"]), "--out", str(out), "--views", "2", "--width", "16",
            "--height", "12", "--resolution", "16", "--device", "cpu"]  # fmt: skip


def test_mask_png_is_the_mask_used_and_reads_back_with_mask(trained_runs, photo, tmp_path):
    out = tmp_path / "pred"
    assert main(_tiny_args(trained_runs, out) + ["--image", str(photo["rgb"])]) == 0
    summary = json.loads((out / "prediction.json").read_text())
    mask = np.asarray(Image.open(out / "mask.png"))
    assert "mask.png" in summary["files"] and mask.shape == np.asarray(Image.open(photo["rgb"])).shape[:2]
    assert set(np.unique(mask)) == {0, 255} and summary["separation"]["source"] == "uniform background"
    assert {"agreement", "compared_with", "note", "segmenter_confidence"} <= set(summary["separation"])
    again = tmp_path / "again"
    assert main(_tiny_args(trained_runs, again) + ["--image", str(photo["rgb"]), "--mask", str(out / "mask.png")]) == 0
    assert json.loads((again / "prediction.json").read_text())["object_bbox"] == summary["object_bbox"]
    assert (np.asarray(Image.open(again / "mask.png")) == mask).all()


def test_segment_none_and_bad_segment_values(trained_runs, photo, tmp_path, capsys):
    out = tmp_path / "pred"
    assert main(_tiny_args(trained_runs, out) + ["--image", str(photo["rgb"]), "--segment", "none"]) == 0
    summary = json.loads((out / "prediction.json").read_text())
    assert summary["object_separated_by"] == "whole image" and summary["separation"]["confident"]
    assert np.asarray(Image.open(out / "mask.png")).min() == 255
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        main(_tiny_args(trained_runs, out) + ["--image", str(photo["rgb"]), "--segment", "magic"])
    assert exit_info.value.code == 2 and "magic" in capsys.readouterr().err


def test_a_box_is_recorded_and_one_without_pixels_is_exit_2_keeping_earlier_outputs(
    trained_runs, photo, tmp_path, capsys
):
    out = tmp_path / "pred"
    h, w = np.asarray(Image.open(photo["rgb"])).shape[:2]
    box = ["--box", "0", "0", str(w), str(h)]
    assert main(_tiny_args(trained_runs, out) + ["--image", str(photo["rgb"]), "--fit-steps", "0", *box]) == 0
    summary = json.loads((out / "prediction.json").read_text())
    assert summary["separation"]["box"] == [0, 0, w, h] and summary["separation"]["source"] == "uniform background"
    capsys.readouterr()
    outside = ["--box", str(w + 5), "0", str(w + 50), "10"]
    assert main(_tiny_args(trained_runs, out) + ["--image", str(photo["rgb"]), *outside]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "holds no pixel of the" in err and str(photo["rgb"]) in err
    assert json.loads((out / "prediction.json").read_text()) == summary  # the earlier outputs are kept


def test_segment_salient_without_the_extra_is_exit_2_naming_it(trained_runs, photo, tmp_path, capsys, monkeypatch):
    import sys

    from affnerf.predict import salient

    monkeypatch.setitem(sys.modules, "onnxruntime", None)
    monkeypatch.setattr(salient, "_LOADED", {})
    out = tmp_path / "pred"
    assert main(_tiny_args(trained_runs, out) + ["--image", str(photo["rgb"]), "--segment", "salient"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "pip install 'affnerf[segment]'" in err and not out.exists()


def test_a_cluttered_photo_is_separated_by_a_given_segmenter(trained_runs, train_dataset, trained_segmenter, tmp_path):
    import skimage.data

    from affnerf.data.composite import cut_to_box, paste
    from affnerf.data.dataset import Dataset

    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects("train")[0])
    photo = np.ascontiguousarray(skimage.data.coffee()[::4, ::4])
    rgb, alpha = paste(np.random.default_rng(0), photo, cut_to_box(obj.rgb(0), obj.affordance(0) > 0), (0.5, 0.6))
    Image.fromarray(rgb).save(tmp_path / "clutter.png")
    out = tmp_path / "pred"
    args = ["--image", str(tmp_path / "clutter.png"), "--fit-steps", "0", "--segmenter", str(trained_segmenter)]
    assert main(_tiny_args(trained_runs, out) + args) == 0
    separation = json.loads((out / "prediction.json").read_text())["separation"]
    assert separation["source"] == "segmenter" and 0.5 < separation["segmenter_confidence"] <= 1.0
    mask = np.asarray(Image.open(out / "mask.png")) > 127
    assert (mask & (alpha > 0.5)).sum() / (mask | (alpha > 0.5)).sum() > 0.3


def test_a_segmenter_file_that_is_not_one_is_exit_2_naming_it(trained_runs, tiny_dataset, tmp_path, capsys):
    bad = tmp_path / "seg.pt"
    bad.write_bytes(b"nothing")
    clutter = tmp_path / "clutter.png"
    Image.fromarray(np.random.default_rng(0).integers(0, 255, (60, 80, 3), np.uint8)).save(clutter)
    out = tmp_path / "pred"
    args = _tiny_args(trained_runs, out) + ["--image", str(clutter), "--segmenter", str(bad)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "seg.pt: not an affnerf object segmenter" in err and not out.exists()


def test_segmenter_none_leaves_the_shipped_segmenter_out(trained_runs, photo, tmp_path, capsys):
    clutter = tmp_path / "clutter.png"
    Image.fromarray(np.random.default_rng(0).integers(0, 255, (60, 80, 3), np.uint8)).save(clutter)
    out = tmp_path / "pred"
    args = _tiny_args(trained_runs, out) + ["--image", str(clutter), "--segment", "segmenter", "--segmenter", "none"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--segment segmenter needs a segmenter file" in err and not out.exists()
    auto = _tiny_args(trained_runs, out) + ["--image", str(photo["rgb"]), "--fit-steps", "0", "--segmenter", "none"]
    assert main(auto) == 0  # a clean render: auto takes the uniform background, no segmenter needed
    assert json.loads((out / "prediction.json").read_text())["separation"]["source"] == "uniform background"
