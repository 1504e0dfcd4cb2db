"""Overexposed photos: measured over the object's pixels only, and warned about in one line."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.predict.exposure import CLIPPED_LEVEL, OVEREXPOSED_SHARE, clipped_share, overexposure_warning
from affnerf.predict.image import prepare_image


def _photo(object_colour, bg=(255, 255, 255)):
    rgb = np.zeros((90, 120, 3), np.uint8) + np.array(bg, np.uint8)
    rgb[30:60, 40:80] = object_colour
    return rgb


def test_only_the_objects_clipped_pixels_count():
    rgb = _photo((200, 90, 60))  # a white, clipped background around an unclipped object
    mask = np.zeros(rgb.shape[:2], bool)
    mask[30:60, 40:80] = True
    assert clipped_share(rgb, mask) == 0.0
    rgb[30:45, 40:80, 0] = CLIPPED_LEVEL  # one channel of the object's top half at the clipping level
    assert clipped_share(rgb, mask) == 0.5
    rgb[30:45, 40:80, 0] = CLIPPED_LEVEL - 1
    assert clipped_share(rgb, mask) == 0.0
    assert clipped_share(rgb, np.zeros_like(mask)) == 0.0


def test_the_warning_names_the_file_above_the_share_only():
    assert overexposure_warning(Path("p.png"), OVEREXPOSED_SHARE) is None
    line = overexposure_warning(Path("p.png"), 0.6)
    assert line.startswith("p.png: the photo is overexposed (60% of the object's pixels") and "\n" not in line


def test_an_overexposed_photo_is_recorded_and_warned_about_and_a_clean_one_is_not(tmp_path, caplog):
    clean = _photo((200, 90, 60), bg=(240, 240, 240))
    bright = _photo((255, 160, 90), bg=(240, 240, 240))  # red clipped over the whole object
    paths = []
    for name, rgb in (("clean.png", clean), ("bright.png", bright)):
        paths.append(tmp_path / name)
        Image.fromarray(rgb).save(paths[-1])
    with caplog.at_level(logging.WARNING, logger="affnerf.predict.image"):
        plain = prepare_image(paths[0], 32, segment="uniform")
        assert not caplog.records
        over = prepare_image(paths[1], 32, segment="uniform")
    assert plain.exposure_json() == {"clipped_share": 0.0, "overexposed": False}
    assert over.exposure_json() == {"clipped_share": 1.0, "overexposed": True}
    [record] = caplog.records
    assert record.getMessage().startswith(f"{paths[1]}: the photo is overexposed (100%")
