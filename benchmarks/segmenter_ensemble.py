"""Segmenters voting (issue 16): the mean mask IoU of ``auto``'s segmenter mask on the composite benchmark's draws
(``bench_segment.py``'s composites, the same seeded objects, views and placements), for each member alone and for
ensembles of them (:class:`affnerf.model.segmenter.SegmenterEnsemble`: the mean of the members' probability maps,
each member at its own input side), per seed. Every other step is ``auto`` as it ships
(:func:`affnerf.model.segmenter.probability_mask`; with ``--redraw``, also the mask redrawn by GrabCut from the
map, :func:`affnerf.predict.grabcut.refine_with_grabcut`). Each member's map is made once per composite and reused;
a file that holds an ensemble counts as its members (named ``FILE#0``, ``FILE#1``, ...).

Run (two networks, 2026-12-03; a third beside the shipped pair, 2026-12-03 third session)::

    .venv/bin/python benchmarks/segmenter_ensemble.py --data /tmp/seg/data --members STAGE3.pt STAGE4.pt \
        --seeds 1 0 2 3 4 --out benchmarks/results/segmenter_ensemble.json  # its vote was named "ensemble" then
    .venv/bin/python benchmarks/segmenter_ensemble.py --members SHIPPED.pt THIRD.pt --vote 0,1 --vote 0,1,2 \
        --vote 0,2 --vote 1,2 --redraw --out benchmarks/results/segmenter_ensemble3.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import grabcut
from affnerf.predict.segment import mask_iou

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402


def read_members(paths: list[Path]) -> dict[str, segnet.Segmenter]:
    """The single networks in ``paths`` by name, an ensemble's members as ``FILE#i``."""
    members: dict[str, segnet.Segmenter] = {}
    for path in paths:
        nets = segnet.networks(segnet.read_segmenter(path))
        members.update({str(path): nets[0]} if len(nets) == 1 else {f"{path}#{i}": m for i, m in enumerate(nets)})
    return members


def vote_name(vote: list[int]) -> str:
    return "vote " + "+".join(map(str, vote))


def composite_ious(rgb: np.ndarray, truth: np.ndarray, maps: dict[str, np.ndarray], redraw: bool) -> dict:
    """IoU of each map's mask with ``truth``, and of that mask redrawn by GrabCut (``NAME, redrawn``)."""
    row = {}
    for name, prob in maps.items():
        mask = segnet.probability_mask(prob)
        row[name] = round(mask_iou(mask, truth), 4)
        if redraw:
            refined = grabcut.refine_with_grabcut(rgb, mask, prob) if mask.any() else mask
            row[f"{name}, redrawn"] = round(mask_iou(refined, truth), 4)
    return row


def seed_scores(
    data: Path, seed: int, count: int, members: dict[str, segnet.Segmenter], votes: list[list[int]], redraw: bool
) -> dict:
    """Mean mask IoU of each member's mask and of each vote's for one seed's composites, and the composites where
    they differ by more than 0.1."""
    names = list(members)
    rows, moved = [], []
    for c in bench_composites(data, seed, count):
        maps = {name: segnet.object_probability(model, c.rgb) for name, model in members.items()}
        for vote in votes:  # as the ensemble's own map, from maps made once
            maps[vote_name(vote)] = segnet.vote([maps[names[i]] for i in vote])
        row = composite_ious(c.rgb, c.truth, maps, redraw)
        rows.append(row)
        if max(row.values()) - min(row.values()) > 0.1:
            moved.append({"index": c.index, "object": c.obj.record.object_id, "background": c.background, **row})
    means = {k: round(float(np.mean([r[k] for r in rows])), 4) for k in rows[0]}
    return {"mean_iou": means, "composites_that_move": moved}


def parse_vote(text: str) -> list[int]:
    return [int(i) for i in text.split(",")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--members", type=Path, nargs="+", required=True, help="segmenter files")
    parser.add_argument("--vote", type=parse_vote, action="append", help="member indices that vote (default all)")
    parser.add_argument("--redraw", action="store_true", help="also score the masks redrawn by GrabCut")
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 0, 2, 3, 4])
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    members = read_members(args.members)
    votes = args.vote or [list(range(len(members)))]
    sides = {name: model.config.input_side for name, model in members.items()}
    result = {"machine": describe_machine(), "composites": args.composites, "input_sides": sides, "seeds": {}}
    for seed in args.seeds:
        result["seeds"][str(seed)] = seed_scores(args.data, seed, args.composites, members, votes, args.redraw)
        print(seed, json.dumps(result["seeds"][str(seed)]["mean_iou"]), flush=True)
        args.out.write_text(json.dumps(result, indent=1) + "\n")
    names = list(next(iter(result["seeds"].values()))["mean_iou"])
    result["mean_over_seeds"] = {
        n: round(float(np.mean([s["mean_iou"][n] for s in result["seeds"].values()])), 4) for n in names
    }
    print("mean", json.dumps(result["mean_over_seeds"]))
    args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
