"""Preparing photos of any mode and size the way training saw objects."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from PIL import Image

from affnerf.errors import AffnerfError
from affnerf.predict.image import MAX_BORDER_CONTACT, MIN_BACKGROUND_UNIFORMITY, prepare_image


def _photo(width=120, height=90, bg=(240, 240, 240)):
    rgb = np.zeros((height, width, 3), np.uint8) + np.array(bg, np.uint8)
    rgb[30:60, 70:100] = (200, 30, 30)  # a red box right of centre
    return rgb


def _save(tmp_path, name, image):
    path = tmp_path / name
    image.save(path)
    return path


@pytest.mark.parametrize("mode", ["RGB", "L", "P", "I;16", "RGBA", "LA"])
def test_every_mode_gives_the_same_centred_crop(tmp_path, mode):
    rgb = _photo()
    if mode == "RGB":
        image = Image.fromarray(rgb)
    elif mode == "L":
        image = Image.fromarray(rgb).convert("L")
    elif mode == "P":
        image = Image.fromarray(rgb).convert("P", palette=Image.Palette.ADAPTIVE, colors=16)
    elif mode == "I;16":
        grey = np.asarray(Image.fromarray(rgb).convert("L")).astype(np.uint16) * 257
        image = Image.fromarray(grey)
    else:
        alpha = np.zeros(rgb.shape[:2], np.uint8)
        alpha[30:60, 70:100] = 255
        noisy = rgb.copy()
        noisy[alpha == 0] = np.random.default_rng(0).integers(0, 255, (int((alpha == 0).sum()), 3))  # clutter
        image = Image.fromarray(np.dstack([noisy, alpha])).convert(mode)
    prepared = prepare_image(_save(tmp_path, "x.png", image), 32)
    assert prepared.crop.shape == (32, 32, 3)
    assert prepared.bbox == (70, 30, 100, 60)
    assert prepared.source == ("alpha" if mode in ("RGBA", "LA") else "uniform background")
    # the object fills the middle of the crop on the white training background
    assert prepared.crop[0, 0].tolist() == [255, 255, 255]
    assert prepared.crop[16, 16].max() < 250


def test_mask_file_and_any_size(tmp_path):
    rgb = np.random.default_rng(1).integers(0, 255, (301, 517, 3)).astype(np.uint8)  # no uniform background at all
    mask = np.zeros((301, 517), np.uint8)
    mask[100:200, 300:350] = 255
    prepared = prepare_image(
        _save(tmp_path, "n.jpg", Image.fromarray(rgb)), 48, mask=_save(tmp_path, "m.png", Image.fromarray(mask))
    )
    assert prepared.bbox == (300, 100, 350, 200) and prepared.source == "mask"


def test_blank_missing_and_mismatched_inputs_are_clear_errors(tmp_path):
    blank = _save(tmp_path, "blank.png", Image.new("RGB", (64, 48), (12, 200, 7)))
    with pytest.raises(AffnerfError, match=r"blank\.png: no object found"):
        prepare_image(blank, 32)
    with pytest.raises(AffnerfError, match=r"nope\.png: file not found"):
        prepare_image(tmp_path / "nope.png", 32)
    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\nxxxx")
    with pytest.raises(AffnerfError, match=r"bad\.png: cannot read image"):
        prepare_image(tmp_path / "bad.png", 32)
    photo = _save(tmp_path, "p.png", Image.fromarray(_photo()))
    small_mask = _save(tmp_path, "small.png", Image.new("L", (10, 10), 255))
    with pytest.raises(AffnerfError, match=r"small\.png: mask is 10x10, the image 120x90"):
        prepare_image(photo, 32, mask=small_mask)


def _noise(width=120, height=90):
    return np.random.default_rng(2).integers(0, 256, (height, width, 3)).astype(np.uint8)


def _gradient(width=120, height=90):
    ramp = np.linspace(0, 255, width)[None, :, None]
    return np.broadcast_to(ramp, (height, width, 3)).round().astype(np.uint8)


@pytest.mark.parametrize("kind", ["noise", "gradient"])
def test_an_image_without_uniform_background_is_doubtful_by_its_border_with_one_warning(tmp_path, caplog, kind):
    rgb = _noise() if kind == "noise" else _gradient()
    path = _save(tmp_path, f"{kind}.png", Image.fromarray(rgb))
    with caplog.at_level(logging.WARNING, logger="affnerf"):
        prepared = prepare_image(path, 32, segment="uniform")
    sep = prepared.separation
    assert sep.source == "uniform background" and not sep.confident
    assert sep.background_uniformity < MIN_BACKGROUND_UNIFORMITY and sep.border_contact > MAX_BORDER_CONTACT
    assert sep.problems[0].startswith("no uniform background: ")
    assert sep.to_json()["confident"] is False and sep.to_json()["problems"] == list(sep.problems)
    (record,) = caplog.records
    assert record.getMessage().startswith(f"{path}: the object could not be separated with confidence (no uniform")
    assert "give the object's mask with --mask FILE" in record.getMessage() and "\n" not in record.getMessage()


def test_a_clean_photo_is_confident_and_a_mask_is_never_doubted(tmp_path, caplog):
    with caplog.at_level(logging.WARNING, logger="affnerf"):
        clean = prepare_image(_save(tmp_path, "p.png", Image.fromarray(_photo())), 32).separation
        mask = np.zeros((90, 120), np.uint8)
        mask[:, :100] = 255  # most of the frame, along its border: the user's word for it
        masked = prepare_image(_save(tmp_path, "n.png", Image.fromarray(_noise())), 32,
                               mask=_save(tmp_path, "m.png", Image.fromarray(mask))).separation  # fmt: skip
    assert clean.confident and clean.background_uniformity == 1.0 and clean.border_contact == 0.0
    assert clean.object_fraction == pytest.approx(30 * 30 / (120 * 90))
    assert masked.confident and masked.background_uniformity is None and masked.object_fraction > 0.8
    assert not clean.cut_off and masked.cut_off  # not doubted, but the mask runs off the photo: said once
    [record] = caplog.records
    assert "n.png: the object reaches the edge of the photo" in record.getMessage()


def test_a_blank_frame_is_an_error_saying_what_to_give(tmp_path):
    blank = _save(tmp_path, "white.png", Image.new("RGB", (64, 48), (255, 255, 255)))
    with pytest.raises(AffnerfError, match=r"white\.png: no object found \(the image is blank or of one colour\); "
                                           r"give a photo of an object"):  # fmt: skip
        prepare_image(blank, 32)
    empty = _save(tmp_path, "empty_mask.png", Image.new("L", (120, 90), 0))
    with pytest.raises(AffnerfError, match=r"empty_mask\.png: no object found \(the mask is empty\); give a mask"):
        prepare_image(_save(tmp_path, "p.png", Image.fromarray(_photo())), 32, mask=empty)


def test_segment_none_takes_the_whole_image_and_is_never_doubted(tmp_path, caplog):
    with caplog.at_level(logging.WARNING, logger="affnerf"):
        prepared = prepare_image(_save(tmp_path, "n.png", Image.fromarray(_noise())), 32, segment="none")
    assert prepared.source == "whole image" and prepared.mask.all() and prepared.bbox == (0, 0, 120, 90)
    assert prepared.separation.confident and not caplog.records


def test_a_mask_file_overrides_the_segment_method_and_alpha_is_used_by_auto_only(tmp_path):
    rgb = _photo()
    mask = np.zeros((90, 120), np.uint8)
    mask[10:20, 10:30] = 255
    masked = prepare_image(_save(tmp_path, "p.png", Image.fromarray(rgb)), 32, mask=_save(tmp_path, "m.png",
                           Image.fromarray(mask)), segment="none")  # fmt: skip
    assert masked.source == "mask" and masked.bbox == (10, 10, 30, 20)
    alpha = np.zeros((90, 120), np.uint8)
    alpha[0:10, 0:10] = 255
    rgba = _save(tmp_path, "a.png", Image.fromarray(np.dstack([rgb, alpha])))
    assert prepare_image(rgba, 32).source == "alpha"
    assert prepare_image(rgba, 32, segment="uniform").bbox == (70, 30, 100, 60)


def test_two_methods_that_disagree_make_a_doubtful_separation():
    from affnerf.predict.image import MIN_AGREEMENT, measure_separation
    from affnerf.predict.segment import Segmentation

    rgb, mask = _photo(), np.zeros((90, 120), bool)
    mask[30:60, 70:100] = True
    seg = Segmentation(mask, "salient", agreement=MIN_AGREEMENT - 0.1, compared_with="grabcut")
    sep = measure_separation(rgb, mask, "salient", seg)
    assert not sep.confident and sep.problems == ("two separation methods agree on only 70% (IoU) of the object",)
    record = sep.to_json()
    assert record["source"] == "salient" and record["agreement"] == 0.7 and record["compared_with"] == "grabcut"
    assert record["background_uniformity"] is None and record["note"] is None


def test_a_box_confines_the_separation_and_is_recorded(tmp_path):
    rgb = _photo()
    rgb[5:15, 5:15] = (30, 30, 200)  # something else, outside the box
    path = _save(tmp_path, "two.png", Image.fromarray(rgb))
    prepared = prepare_image(path, 64, segment="uniform", box=(60, 20, 110, 70))
    assert prepared.bbox == (70, 30, 100, 60) and not prepared.mask[:20].any()
    assert prepared.separation.to_json()["box"] == [60, 20, 110, 70]
    assert prepare_image(path, 64, segment="uniform").separation.to_json()["box"] is None
    with pytest.raises(AffnerfError, match="two.png: --box 200 0 300 50 holds no pixel"):
        prepare_image(path, 64, box=(200, 0, 300, 50))


def test_an_object_running_off_the_photo_is_recorded_and_warned_about_once(tmp_path, caplog):
    whole = _photo()
    cut = whole.copy()
    cut[30:60, 100:120] = (200, 30, 30)  # the box now runs off the right edge
    with caplog.at_level(logging.WARNING, logger="affnerf.predict.image"):
        inside = prepare_image(_save(tmp_path, "whole.png", Image.fromarray(whole)), 32, segment="uniform")
        assert not caplog.records
        prepared = prepare_image(_save(tmp_path, "cut.png", Image.fromarray(cut)), 32, segment="uniform")
    assert not inside.separation.cut_off and inside.separation.to_json()["cut_off"] is False
    assert prepared.separation.cut_off and prepared.separation.to_json()["cut_off"] is True
    assert prepared.separation.confident  # the mask itself is fine: only the view is wanting
    [record] = caplog.records
    assert record.getMessage().startswith(f"{tmp_path / 'cut.png'}: the object reaches the edge of the photo")


def test_a_checker_model_sees_where_the_photo_ends_and_a_whole_object_is_cropped_as_before(tmp_path):
    cut = _photo()
    cut[30:60, 100:120] = (200, 30, 30)  # runs off the right edge
    for name, rgb in (("whole.png", _photo()), ("cut.png", cut)):
        path = _save(tmp_path, name, Image.fromarray(rgb))
        plain = prepare_image(path, 32, segment="uniform")
        marked = prepare_image(path, 32, segment="uniform", outside="checker")
        changed = (plain.crop != marked.crop).any(-1)
        assert changed.any() == (name == "cut.png")
        assert set(np.unique(marked.crop[changed]).tolist()) <= {0, 255}
