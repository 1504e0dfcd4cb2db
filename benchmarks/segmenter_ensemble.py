"""Two segmenters voting (issue 16): the mean mask IoU of ``auto``'s segmenter mask on the composite benchmark's
draws (``bench_segment.py``'s composites, the same seeded objects, views and placements), for each member alone and
for their ensemble (:class:`affnerf.model.segmenter.SegmenterEnsemble`: the mean of the members' probability maps,
each member at its own input side), per seed. Every other step is ``auto`` as it ships
(:func:`affnerf.model.segmenter.probability_mask`). Each member's map is made once per composite and reused.

Run::

    .venv/bin/python benchmarks/segmenter_ensemble.py --data /tmp/seg/data --members STAGE3.pt STAGE4.pt \
        --seeds 1 0 2 3 4 --out benchmarks/results/segmenter_ensemble.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict.segment import mask_iou

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402


def seed_scores(data: Path, seed: int, count: int, members: dict[str, segnet.AnySegmenter]) -> dict:
    """Mean mask IoU of each member's mask and of the ensemble's for one seed's composites, and the composites
    where they differ by more than 0.1."""
    ious: dict[str, list[float]] = {name: [] for name in [*members, "ensemble"]}
    moved = []
    for c in bench_composites(data, seed, count):
        maps = {name: segnet.object_probability(model, c.rgb) for name, model in members.items()}
        maps["ensemble"] = segnet.vote(list(maps.values()))  # as the ensemble's own map, from maps made once
        row = {name: round(mask_iou(segnet.probability_mask(p), c.truth), 4) for name, p in maps.items()}
        for name, value in row.items():
            ious[name].append(value)
        if max(row.values()) - min(row.values()) > 0.1:
            moved.append({"index": c.index, "object": c.obj.record.object_id, "background": c.background, **row})
    return {"mean_iou": {k: round(float(np.mean(v)), 4) for k, v in ious.items()}, "composites_that_move": moved}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--members", type=Path, nargs="+", required=True, help="segmenter files")
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 0, 2, 3, 4])
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    members = {str(path): segnet.read_segmenter(path) for path in args.members}
    sides = {name: model.config.input_side for name, model in members.items()}
    result = {"machine": describe_machine(), "composites": args.composites, "input_sides": sides, "seeds": {}}
    for seed in args.seeds:
        result["seeds"][str(seed)] = seed_scores(args.data, seed, args.composites, members)
        print(seed, json.dumps(result["seeds"][str(seed)]["mean_iou"]), flush=True)
    names = [*members, "ensemble"]
    result["mean_over_seeds"] = {
        n: round(float(np.mean([s["mean_iou"][n] for s in result["seeds"].values()])), 4) for n in names
    }
    print("mean", json.dumps(result["mean_over_seeds"]))
    args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
