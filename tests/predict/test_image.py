"""Preparing photos of any mode and size the way training saw objects."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from affnerf.errors import AffnerfError
from affnerf.predict.image import prepare_image


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
    prepared = prepare_image(_save(tmp_path, "n.jpg", Image.fromarray(rgb)), 48, mask=_save(tmp_path, "m.png", Image.fromarray(mask)))
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
