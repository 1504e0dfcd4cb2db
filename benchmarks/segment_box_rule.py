"""Choosing how ``--segment auto`` separates inside a ``--box``: the object segmenter's mask of the whole photo cut
to the box, GrabCut in the box, or the first when the segmenter is sure enough (issue 16).

On the composites of ``bench_segment.py`` (the same seeded draws and boxes), for each composite and box (loose: the
true box 5-25 % larger per side; tight: 0-5 %): the IoU with the true mask of the shipped segmenter's mask of the
whole photo made inside the box (``segmenter_segmentation``), its confidence (mean probability over that mask), and
the IoU of GrabCut from the box (``segment_in_box`` with no segmenter). Prints the mean IoU of the rule "the
segmenter's mask when its confidence is at least T, else GrabCut" for several T;
``segment.BOX_SEGMENTER_CONFIDENCE`` was chosen on ``--seed 1`` and checked on ``--seed 0``.

Run::

    .venv/bin/python benchmarks/segment_box_rule.py --seed 1 --out benchmarks/results/segment_box_rule_seed1.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from affnerf.model import segmenter as segnet
from affnerf.predict import segment

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402

THRESHOLDS = (0.4, 0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9, 0.93, 0.95)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    model = segnet.load_segmenter(segment.resolve_segmenter(None))
    rows = []
    for c in bench_composites(args.data, args.seed, args.composites):
        for kind, box in (("loose", c.box), ("tight", c.tight_box)):
            seg = segment.segmenter_segmentation(c.rgb, model, box)
            grabcut = segment.segment_in_box(c.rgb, box, segmenter=segment.NO_SEGMENTER)
            rows.append({"object": c.obj.record.object_id, "background": c.background, "box": kind,
                         "confidence": seg.confidence, "segmenter": segment.mask_iou(seg.mask, c.truth),
                         "grabcut": segment.mask_iou(grabcut.mask, c.truth)})  # fmt: skip
    summary = {}
    for kind in ("loose", "tight"):
        r = [x for x in rows if x["box"] == kind]
        summary[kind] = {
            "segmenter": np.mean([x["segmenter"] for x in r]),
            "grabcut": np.mean([x["grabcut"] for x in r]),
        }
        for t in THRESHOLDS:
            summary[kind][f"rule {t}"] = np.mean([x["segmenter"] if x["confidence"] >= t else x["grabcut"] for x in r])
        summary[kind] = {m: round(float(v), 4) for m, v in summary[kind].items()}
    print(json.dumps(summary, indent=1))
    args.out.write_text(json.dumps({"seed": args.seed, "summary": summary, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
