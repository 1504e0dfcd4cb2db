"""The demo's overview sheet: one row per example with a mesh, in the order given."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.pictures.sheets import overview_sheet


def _example(folder: Path, value: int, mesh: bool = True) -> Path:
    (folder / "turntable").mkdir(parents=True)
    Image.fromarray(np.full((30, 40, 3), value, np.uint8)).save(folder / "original.png")
    for i in range(6):
        Image.fromarray(np.full((15, 40, 3), value, np.uint8)).save(folder / "turntable" / f"{i:03d}.png")
    if mesh:
        Image.fromarray(np.full((20, 60, 3), value, np.uint8)).save(folder / "mesh_preview.png")
    return folder


def test_overview_has_a_row_per_example_with_a_mesh(tmp_path):
    folders = [_example(tmp_path / "a", 10), _example(tmp_path / "b", 90, mesh=False), _example(tmp_path / "c", 200)]
    sheet = overview_sheet(folders, height=50)
    assert sheet is not None and sheet.dtype == np.uint8
    body = sheet[sheet.shape[0] - 2 * 54 :]
    first, second = body[:50, :60], body[54:104, :60]
    assert (first[:, :60] == 10).all() and (second[:, :60] == 200).all()  # inputs resized to 50 rows: 67 px wide
    assert not (sheet == 90).all(-1).any()  # the example without a mesh is left out
    assert overview_sheet([folders[1]]) is None


def test_dataset_sheet_has_a_row_per_object_and_a_legend(tiny_dataset, tmp_path):
    from affnerf.pictures.sheets import preview_sheet, write_preview

    one = preview_sheet(tiny_dataset, objects=1, views=2, tile_width=40)
    two = preview_sheet(tiny_dataset, objects=2, views=2, tile_width=40)
    assert one.dtype == np.uint8 and one.shape[1] == two.shape[1]
    assert two.shape[0] > one.shape[0]  # one more object row
    path = write_preview(tiny_dataset, tmp_path / "deep" / "sheet.png", objects=1, views=2, tile_width=40)
    assert np.asarray(Image.open(path)).shape == one.shape
