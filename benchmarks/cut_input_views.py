"""How much worse AFF-NeRF predicts from an input view that cuts the object off (issue 12; results/cut_inputs.md).

Reads a stability run's metrics (``affnerf eval --stability-views 4``: every test object predicted from 4 input
views, with each view's mIoU and F@1cm), marks each input view whose object touches the image border in the
dataset's full-resolution affordance map (``affnerf.data.crop.touches_border``), and compares, within each object
that has both kinds of input view, the mean over its cut views with the mean over its whole ones (a paired
difference, so the object's own difficulty cancels). Also counts the cut frames of every split.

    .venv/bin/python benchmarks/cut_input_views.py --data DATA \
        --stability benchmarks/results/stability_64_metrics_affnerf.json --out benchmarks/results/cut_input_views.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.data.crop import touches_border
from affnerf.data.dataset import Dataset


def frame_is_cut(folder: Path, view: int) -> bool:
    """Whether the object of frame ``view`` in an object's ``folder`` touches the image border (its affordance
    map)."""
    return bool(touches_border(np.asarray(Image.open(folder / "affordance" / f"{view:03d}.png")) > 0))


def paired_differences(data: Path, stability: dict) -> dict[str, dict]:
    """Per category: the number of cut input views and, over the objects with both kinds, the mean of (cut views'
    mean - whole views' mean) of mIoU and F@1cm."""
    by_category: dict[str, dict] = {}
    for object_id, scores in stability["objects"].items():
        category = scores["category"]
        cut = np.array([frame_is_cut(data / category / object_id, v[0]) for v in scores["inputs"]])
        entry = by_category.setdefault(category, {"input_views": 0, "cut_views": 0, "pairs": []})
        entry["input_views"] += len(cut)
        entry["cut_views"] += int(cut.sum())
        if cut.any() and (~cut).any():
            miou, fscore = np.array(scores["mIoU"]), np.array(scores["fscore_1cm"])
            entry["pairs"].append([miou[cut].mean() - miou[~cut].mean(), fscore[cut].mean() - fscore[~cut].mean()])
    for entry in by_category.values():
        pairs = np.array(entry.pop("pairs")).reshape(-1, 2)
        entry["objects_with_both"] = len(pairs)
        entry["miou_cut_minus_whole"] = float(pairs[:, 0].mean()) if len(pairs) else None
        entry["fscore_1cm_cut_minus_whole"] = float(pairs[:, 1].mean()) if len(pairs) else None
        entry["_pairs"] = pairs
    return by_category


def cut_frame_shares(data: Path) -> dict[str, dict[str, float]]:
    """Per category and split, the share of frames whose object touches the image border."""
    ds = Dataset.open(data)
    shares: dict[str, dict[str, list[bool]]] = {}
    for entry in ds.objects():
        folder = data / entry.path
        cut = [frame_is_cut(folder, i) for i in range(len(list((folder / "affordance").glob("*.png"))))]
        shares.setdefault(entry.category, {}).setdefault(entry.split, []).extend(cut)
    return {c: {s: float(np.mean(v)) for s, v in sorted(splits.items())} for c, splits in sorted(shares.items())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--stability", type=Path, required=True, help="a stability run's metrics JSON")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    stability = json.loads(args.stability.read_text())["stability"]
    categories = paired_differences(args.data, stability)
    pairs = np.concatenate([c.pop("_pairs") for c in categories.values()])
    overall = {"objects_with_both": len(pairs), "miou_cut_minus_whole": float(pairs[:, 0].mean()),
               "fscore_1cm_cut_minus_whole": float(pairs[:, 1].mean()),
               "objects_worse_from_cut_views_miou": int((pairs[:, 0] < 0).sum()),
               "objects_worse_from_cut_views_fscore": int((pairs[:, 1] < 0).sum())}  # fmt: skip
    result = {"stability": str(args.stability), "categories": categories, "overall": overall,
              "cut_frame_shares": cut_frame_shares(args.data)}  # fmt: skip
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    for name, entry in sorted(categories.items()):
        print(name, entry)
    print("overall", overall)


if __name__ == "__main__":
    main()
