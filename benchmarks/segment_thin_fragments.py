"""Thin fragments beside the object (issue 16): keep a region of the segmenter's mask that is less than
:data:`~affnerf.model.segmenter.SEGMENTER_EXTRA_CONFIDENCE` sure when it is thin (a shaft, a bail cut off from the
handle by a pixel or two the segmenter doubts) and touches the main region, on the composites of
``bench_segment.py`` (the same seeded draws).

A region is *thin* when :func:`affnerf.predict.grabcut.thin_parts` at ``radius`` (a share of the photo's larger side)
keeps at least ``share`` of it. Each rule adds to :func:`~affnerf.model.segmenter.probability_mask`'s mask (as it
ships) every thin region at least ``least`` sure on average whose gap to the main region is at most ``gap`` of the
photo's larger side; the mask is then redrawn by GrabCut as ``auto`` does. Mean mask IoU, thin-part recall
(``bench_segment.thin_recall``) and every composite a rule changes, per seed.

Run::

    .venv/bin/python benchmarks/segment_thin_fragments.py --data /tmp/seg/data --seeds 1 --out OUT.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch
from scipy import ndimage

from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import grabcut
from affnerf.predict.segment import resolve_segmenter

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites, seed_sweep_parser  # noqa: E402
from segmenter_thin import score  # noqa: E402

#: (radius, share thin, least mean probability, largest gap) of each rule; None = the mask as it ships.
RULES = (
    [None]
    + [(0.0075, 0.7, p, g) for p in (0.4, 0.5, 0.6) for g in (0.01, 0.02, 0.04)]
    + [(0.0125, 0.7, 0.5, 0.02), (0.0075, 0.5, 0.5, 0.02), (0.0075, 0.9, 0.5, 0.02)]
)


def rule_name(rule: tuple | None) -> str:
    return "ships" if rule is None else "radius {}, thin {}, sure {}, gap {}".format(*rule)


def thin_fragments(prob: np.ndarray, mask: np.ndarray, rule: tuple) -> np.ndarray:
    """(H, W) bool: the hysteresis regions of ``prob`` outside ``mask`` that ``rule`` keeps (see the module doc)."""
    radius, share, least, gap = rule
    found = segnet.hysteresis_mask(prob) & ~mask
    labels, count = ndimage.label(found, structure=np.ones((3, 3)))
    if count == 0 or not mask.any():
        return np.zeros_like(mask)
    index = np.arange(1, count + 1)
    thin = grabcut.thin_parts(found, radius)
    thin_share = ndimage.sum(thin, labels, index) / ndimage.sum(found, labels, index)
    means = ndimage.mean(prob, labels, index)
    gaps = np.asarray(ndimage.minimum(ndimage.distance_transform_edt(~mask), labels, index))
    keep = (thin_share >= share) & (means >= least) & (gaps <= gap * max(mask.shape))
    return np.isin(labels, index[keep])


def rule_score(rgb: np.ndarray, truth: np.ndarray, prob: np.ndarray, rule: tuple | None) -> dict:
    """:func:`segmenter_thin.score` of the shipped mask with ``rule``'s thin fragments added."""
    mask = segnet.probability_mask(prob)
    return score(rgb, truth, prob, mask if rule is None else mask | thin_fragments(prob, mask, rule))


def seed_result(data: Path, seed: int, count: int, model) -> dict:
    rows = []
    for c in bench_composites(data, seed, count):
        prob = segnet.photo_probability(model, c.rgb)
        row = {"index": c.index, "object": c.obj.record.object_id, "background": c.background}
        row.update({rule_name(r): rule_score(c.rgb, c.truth, prob, r) for r in RULES})
        rows.append(row)
        print(json.dumps(row), flush=True)
    summary = {}
    for r in map(rule_name, RULES):
        thin = [row[r]["thin"] for row in rows if row[r]["thin"] is not None]
        summary[r] = {"mean_iou": round(float(np.mean([row[r]["iou"] for row in rows])), 4),
                      "thin_recall": round(float(np.mean(thin)), 4) if thin else None}  # fmt: skip
    return {"summary": summary, "per_composite": rows}


def main() -> None:
    ap = seed_sweep_parser(__doc__)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    model = segnet.load_segmenter(resolve_segmenter(None))
    result = {"machine": describe_machine(), "seeds": {}}
    for seed in args.seeds:
        result["seeds"][str(seed)] = seed_result(args.data, seed, args.composites, model)
        args.out.write_text(json.dumps(result, indent=1))
    print(json.dumps({s: v["summary"] for s, v in result["seeds"].items()}, indent=1))


if __name__ == "__main__":
    main()
