"""Networks of the object segmenter swapped in and out of the shipped vote (issue 16), scored as ``auto`` reads a
photo: mean mask IoU and thin-part recall (``bench_segment.thin_recall``: the share of the true mask's thin parts
kept) of the mask redrawn by GrabCut, per seed of the composite benchmark's draws (``bench_composites``).

Each member's whole-photo map and corner-tile map (:func:`affnerf.model.segmenter.object_probability`,
:func:`~affnerf.model.segmenter.tiled_probability`) are made once per composite; a vote's map is then the larger of
the members' mean whole map and their mean tile map, which is what :func:`~affnerf.model.segmenter.
photo_probability` gives the ensemble (both are means, so they commute). The rest is ``auto`` as it ships
(:func:`~affnerf.model.segmenter.probability_mask`, :func:`affnerf.predict.grabcut.refine_with_grabcut`).

Run (2026-12-05, a network trained with thin parts weighted beside the shipped pair)::

    .venv/bin/python benchmarks/segmenter_thin.py --data /tmp/seg/data --members SHIPPED.pt THIN.pt \
        --vote 0,1 --vote 0,2 --vote 0,1,2 --vote 2 --seeds 1 --out OUT.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch

from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import grabcut
from affnerf.predict.segment import mask_iou

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites, seed_sweep_parser  # noqa: E402
from bench_segment import thin_recall  # noqa: E402
from segmenter_ensemble import parse_vote, read_members, vote_name  # noqa: E402


def member_maps(model: segnet.Segmenter, rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(whole, tiles): the member's (H, W) map of the whole photo and of its four corner tiles."""
    return segnet.object_probability(model, rgb), segnet.tiled_probability(model, rgb)


def vote_map(maps: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """(H, W) the ensemble's photo probability from its members' (whole, tiles) maps."""
    return np.maximum(segnet.vote([w for w, _ in maps]), segnet.vote([t for _, t in maps]))


def score(rgb: np.ndarray, truth: np.ndarray, prob: np.ndarray, mask: np.ndarray | None = None) -> dict:
    """Mask IoU, thin-part recall and confidence of ``auto``'s redrawn mask from the photo probability ``prob``
    (the network's mask ``mask``, or :func:`~affnerf.model.segmenter.probability_mask`'s)."""
    mask = segnet.probability_mask(prob) if mask is None else mask
    redrawn = grabcut.refine_with_grabcut(rgb, mask, prob) if mask.any() else mask
    return {"iou": round(mask_iou(redrawn, truth), 4), "thin": thin_recall(redrawn, truth),
            "confidence": round(segnet.mask_confidence(prob, mask), 4)}  # fmt: skip


def seed_rows(data: Path, seed: int, count: int, members: dict, votes: list[list[int]]) -> list[dict]:
    """One row per composite: each vote's score."""
    names, rows = list(members), []
    for c in bench_composites(data, seed, count):
        maps = [member_maps(members[n], c.rgb) for n in names]
        row = {"index": c.index, "object": c.obj.record.object_id, "background": c.background}
        for vote in votes:
            row[vote_name(vote)] = score(c.rgb, c.truth, vote_map([maps[i] for i in vote]))
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def summary(rows: list[dict], votes: list[list[int]]) -> dict:
    """Per vote: mean IoU, mean thin recall over the objects with thin parts, and share of masks at IoU ≥ 0.9."""
    out = {}
    for vote in votes:
        got = [r[vote_name(vote)] for r in rows]
        thin = [g["thin"] for g in got if g["thin"] is not None]
        out[vote_name(vote)] = {
            "mean_iou": round(float(np.mean([g["iou"] for g in got])), 4),
            "thin_recall": round(float(np.mean(thin)), 4) if thin else None,
            "objects_with_thin_parts": len(thin),
            "share_iou_0.9": round(float(np.mean([g["iou"] >= 0.9 for g in got])), 4),
        }
    return out


def main() -> None:
    ap = seed_sweep_parser(__doc__)
    ap.add_argument("--members", type=Path, nargs="+", required=True, help="segmenter files (ensembles split)")
    ap.add_argument("--vote", type=parse_vote, action="append", required=True, help="member indices, e.g. 0,1")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    members = read_members(args.members)
    result = {"machine": describe_machine(), "members": list(members), "seeds": {}}
    for seed in args.seeds:
        rows = seed_rows(args.data, seed, args.composites, members, args.vote)
        result["seeds"][str(seed)] = {"summary": summary(rows, args.vote), "per_composite": rows}
        args.out.write_text(json.dumps(result, indent=1))
    print(json.dumps({s: v["summary"] for s, v in result["seeds"].items()}, indent=1))


if __name__ == "__main__":
    main()
