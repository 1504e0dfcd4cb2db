"""Contact sheets: a dataset's objects and views (RGB | depth | affordance overlay, with a legend), and the demo's
overview of prediction folders (input | novel view | labelled mesh | grasps)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.errors import AffnerfError
from affnerf.pictures.compose import (
    depth_to_color,
    fit_height,
    grid,
    legend,
    overlay_affordance,
    stack_rows,
    text_strip,
)


def preview_sheet(
    root: Path,
    objects: int = 8,
    views: int = 3,
    split: str | None = None,
    tile_width: int = 200,
) -> np.ndarray:
    """Build the contact sheet of a dataset.

    Args:
        root: dataset root.
        objects: how many objects (spread over categories: round-robin by category, categories by name).
        views: views per object (evenly spaced through its frames).
        split: only objects of this split, if given.
        tile_width: width of each image tile in pixels.

    Returns:
        (H, W, 3) uint8 sheet: one row per object (its id above it), three tiles per view, a legend below.
    """
    ds = Dataset.open(root)
    entries = ds.objects(split=split)
    if not entries:
        raise AffnerfError(f"{Path(root) / 'dataset.json'}: no objects{f' in split {split}' if split else ''}")
    chosen = interleave_categories(entries)[:objects]
    rows, present = [], set()
    for entry in chosen:
        obj = ds.load_object(entry)
        tiles = []
        for i in np.linspace(0, len(obj) - 1, views).round().astype(int):
            rgb, depth, aff = obj.rgb(i), obj.depth(i), obj.affordance(i)
            present |= set(np.unique(aff).tolist())
            for tile in (rgb, depth_to_color(depth), overlay_affordance(rgb, aff)):
                h = round(tile.shape[0] * tile_width / tile.shape[1])
                tiles.append(np.asarray(Image.fromarray(tile).resize((tile_width, h), Image.NEAREST)))
        body = grid([tiles], pad=2)
        rows.append(
            stack_rows([text_strip(f"{entry.id} ({entry.split})  rgb | depth | affordance", body.shape[1]), body])
        )
    sheet = stack_rows(rows)
    ids = sorted(c for c in present if c > 0)
    return stack_rows([sheet, legend(ids, ds.affordance_classes, sheet.shape[1])])


def write_preview(root: Path, out: Path, **kwargs: int | str | None) -> Path:
    """Write :func:`preview_sheet` as a PNG (parent folders are created)."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(preview_sheet(root, **kwargs)).save(out)  # type: ignore[arg-type]
    return out


def overview_sheet(folders: Sequence[Path], height: int = 150) -> np.ndarray | None:
    """(H, W, 3) uint8: one row per demo example folder, input | a novel view (RGB | affordance) | the labelled
    mesh | the best grasps; folders without a mesh are left out (None when none has one)."""
    rows = []
    for folder in folders:
        folder = Path(folder)
        original = next(iter(sorted(folder.glob("original.*"))), None)
        turntable = sorted((folder / "turntable").glob("*.png"))
        if original is None or not turntable or not (folder / "mesh_preview.png").is_file():
            continue
        row = [
            fit_height(np.asarray(Image.open(p)), height)
            for p in (original, turntable[len(turntable) // 6], folder / "mesh_preview.png")
        ]
        if (folder / "grasps" / "grasps.png").is_file():
            row.append(fit_height(np.asarray(Image.open(folder / "grasps" / "grasps.png")), height))
        rows.append(np.concatenate([np.pad(im, ((0, 0), (0, 4), (0, 0)), constant_values=255) for im in row], axis=1))
    if not rows:
        return None
    header = text_strip(
        "input   |   novel view: colour | affordance   |   labelled mesh   |   grasps", rows[0].shape[1]
    )
    return stack_rows([header, *[np.pad(r, ((0, 4), (0, 0), (0, 0)), constant_values=255) for r in rows]])
