"""Which region of the segmenter's mask is the object (issue 16): the main region chosen as the largest size ×
(mean probability) ** k, for several k, among the regions of at least a share of the largest one's size, on the
composites of ``bench_segment.py`` (the same seeded draws). Everything else is
:func:`affnerf.model.segmenter.probability_mask` as it ships (hysteresis, sure nearby fragments). Mean mask IoU
against the true mask per seed, and every composite whose IoU depends on the choice.

Run::

    .venv/bin/python benchmarks/segment_region_rule.py --data /tmp/seg/data --seeds 1 2 0 \
        --out benchmarks/results/segment_region_rule.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict.segment import mask_iou, resolve_segmenter

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402

#: (power, least share of the largest region's size) pairs; at 200 the surest region nearly always wins (one 1 %
#: surer is preferred to one 7 times its size).
RULES = [(k, 0.0) for k in (0, 4, 6, 8, 12, 16, 32, 200)] + [(8, f) for f in (0.05, 0.1, 0.25, 0.5)]


def name(rule: tuple[float, float]) -> str:
    return f"power {rule[0]}, floor {rule[1]}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 0])
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    model = segnet.load_segmenter(resolve_segmenter(None))
    result = {"machine": describe_machine(), "composites": args.composites, "seeds": {}}
    for seed in args.seeds:
        ious: dict[str, list[float]] = {name(r): [] for r in RULES}
        changed = []
        for c in bench_composites(args.data, seed, args.composites):
            prob = segnet.object_probability(model, c.rgb)
            row = {name(r): round(mask_iou(segnet.probability_mask(prob, None, *r), c.truth), 4) for r in RULES}
            for key, value in row.items():
                ious[key].append(value)
            if len(set(row.values())) > 1:
                changed.append({"index": c.index, "object": c.obj.record.object_id, "background": c.background, **row})
        means = {key: round(float(np.mean(v)), 4) for key, v in ious.items()}
        result["seeds"][str(seed)] = {"mean_iou": means, "composites_that_depend_on_the_rule": changed}
        print(seed, json.dumps(means), flush=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
