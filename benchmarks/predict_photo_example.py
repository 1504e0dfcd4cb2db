"""The README's example of ``affnerf predict`` on cluttered photos: ``docs/predict_photo.png``.

Each example is one of the composites of ``benchmarks/bench_segment.py`` (a rendered object pasted onto a
scikit-image photograph; the same seeded draws, so composite K here is composite K there), saved as ``photo.png``
with no alpha channel, and ``affnerf predict --image photo.png --out DIR`` runs on it with no flags (the shipped
model, ``--segment auto``). Each row of the picture shows the photo | ``DIR/mask.png`` (the mask predict used) |
``DIR/turntable/000.png`` (the predicted object's front view: RGB | affordance overlay), with how predict
separated the object and the mask's IoU against the true mask. The default rows are composite 6 (a screwdriver
on the astronaut photograph: the shipped segmenter finds the thin tool on a photo with its own subject, where the
salient model and GrabCut took the astronaut) and composite 0 (thin scissors on the same photograph, the common
failure of the networks alone, which GrabCut redraws from their probabilities, with a warning), then composite 0
again with ``--box`` (``--boxed 0``: the box ``bench_segment.py`` drew for it, the true bounding box loosened by
5-25 % per side; drawn on the photo).

Run::

    affnerf data generate --out /tmp/seg/data --objects-per-category 10 --views 4 --seed 7
    .venv/bin/python benchmarks/predict_photo_example.py --data /tmp/seg/data [--rows 1 0] [--keep /tmp/seg/example]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.pictures.compose import fit_height, legend, stack_rows, text_strip
from affnerf.predict.segment import mask_iou
from affnerf.vocab import AFFORDANCE_CLASSES

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402

#: Height in pixels of each panel of the picture.
PANEL_HEIGHT = 200
#: One composite: object id, background name, (H, W, 3) uint8 photo, (H, W) bool true mask, bench_segment's box.
Case = tuple[str, str, np.ndarray, np.ndarray, tuple[int, int, int, int]]


def example_cases(data: Path, wanted: list[int], seed: int = 0) -> dict[int, Case]:
    """{k: (object id, background, rgb, true mask, box)} of composites ``wanted`` of ``bench_segment.py --seed
    seed`` (:func:`bench_composites.bench_composites`)."""
    return {c.index: (c.obj.record.object_id, c.background, c.rgb, c.truth, c.box)
            for c in bench_composites(data, seed, max(wanted) + 1) if c.index in wanted}  # fmt: skip


def with_box(photo: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:
    """The photo with the box drawn on it (2 pixels of yellow inside its edges)."""
    x0, y0, x1, y1 = box
    out = photo.copy()
    for sl in ((slice(y0, y0 + 2), slice(x0, x1)), (slice(y1 - 2, y1), slice(x0, x1)),
               (slice(y0, y1), slice(x0, x0 + 2)), (slice(y0, y1), slice(x1 - 2, x1))):  # fmt: skip
        out[sl] = (255, 220, 0)
    return out


def row(k: int, object_id: str, background: str, photo: np.ndarray, out: Path, iou: float) -> tuple[np.ndarray, set]:
    """One row of the picture (a caption over photo | mask.png | turntable/000.png) and the classes predicted."""
    summary = json.loads((out / "prediction.json").read_text())
    mask = np.asarray(Image.open(out / "mask.png").convert("RGB"))
    view = np.asarray(Image.open(out / "turntable" / "000.png").convert("RGB"))
    gap = np.full((PANEL_HEIGHT, 6, 3), 255, np.uint8)
    panels = [fit_height(p, PANEL_HEIGHT) for p in (photo, mask, view)]
    body = np.concatenate([panels[0], gap, panels[1], gap, panels[2]], axis=1)
    sep = summary["separation"]
    doubt = "confident" if sep["confident"] else "doubtful: warned on stderr"
    agreement = "" if sep["agreement"] is None else f", agreement with {sep['compared_with']} {sep['agreement']:.2f}"
    boxed = "" if sep["box"] is None else f", --box {' '.join(map(str, sep['box']))}"
    caption = (f"composite {k}{boxed}: {object_id} on skimage '{background}'  |  mask.png: {sep['source']}{agreement} "
               f"({doubt}); IoU with the true mask {iou:.2f}  |  turntable/000.png: RGB | affordance")  # fmt: skip
    ids = {AFFORDANCE_CLASSES.index(name) for name in summary["classes_present"]}
    space = np.full((8, body.shape[1], 3), 255, np.uint8)
    return stack_rows([text_strip(caption, body.shape[1], 18), body, space]), ids


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--rows", type=int, nargs="+", default=[6, 0], help="composites of bench_segment.py")
    parser.add_argument("--boxed", type=int, nargs="*", default=[0], help="composites also predicted with --box")
    parser.add_argument("--seed", type=int, default=0, help="bench_segment.py's --seed")
    parser.add_argument("--keep", type=Path, default=None, help="keep each photo.png and predict's folder here")
    parser.add_argument("--picture", type=Path, default=Path(__file__).parents[1] / "docs" / "predict_photo.png")
    args = parser.parse_args()
    cases = example_cases(args.data, args.rows + args.boxed, args.seed)
    rows, ids = [], set()
    with tempfile.TemporaryDirectory() as tmp:
        for k, boxed in [(k, False) for k in args.rows] + [(k, True) for k in args.boxed]:
            object_id, background, rgb, truth, box = cases[k]
            work = (args.keep or Path(tmp)) / f"composite_{k}{'_box' if boxed else ''}"
            work.mkdir(parents=True, exist_ok=True)
            photo, out = work / "photo.png", work / "out"
            Image.fromarray(rgb).save(photo)
            affnerf = Path(sys.executable).with_name("affnerf")
            flags = ["--box", *map(str, box)] if boxed else []
            subprocess.run([str(affnerf), "predict", "--image", str(photo), "--out", str(out), *flags], check=True)
            iou = mask_iou(np.asarray(Image.open(out / "mask.png")) > 127, truth)
            shown = with_box(rgb, box) if boxed else rgb
            picture_row, classes = row(k, object_id, background, shown, out, iou)
            rows.append(picture_row)
            ids |= classes
            print(f"composite {k} ({object_id} on {background}): mask IoU {iou:.3f}")
    width = max(r.shape[1] for r in rows)
    sheet = stack_rows([*rows, legend(sorted(ids), list(AFFORDANCE_CLASSES), width)])
    args.picture.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(sheet).quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(args.picture, optimize=True)
    print(f"-> {args.picture} ({args.picture.stat().st_size // 1024} kB)")


if __name__ == "__main__":
    main()
