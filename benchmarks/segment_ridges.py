"""Thin ridges beside the mask (issue 16): let GrabCut decide the thin, contrasted structures that touch the
segmenter's mask, on the composites of ``bench_segment.py`` (the same seeded draws).

Where the segmenter drops a thin part entirely (a screwdriver's shaft on a dark photograph: its probability is
below :data:`~affnerf.predict.grabcut.PROBABILITY_SURE_BACKGROUND`), the probability trimap makes the part sure
background and GrabCut cannot bring it back. A rule here finds the photo's thin structures, the colour top-hat
(:func:`ridge_map`: how much a pixel stands out from what a disc of ``radius`` px leaves after a grey opening or
closing, the largest over the three channels and both polarities) at least ``threshold``, keeps the connected
pieces outside the mask that touch it, lie within ``reach`` of the photo's larger side of it, are mostly thin
(:func:`~affnerf.predict.grabcut.thin_parts` keeps at least 70 % of them) and no larger than the mask, and marks
them "probably object" in the trimap, so GrabCut's colour models decide. Mean mask IoU, thin-part recall
(``bench_segment.thin_recall``) and the share of masks at IoU >= 0.9, per rule and seed.

Run (``--map-cache`` keeps each composite's probability map, the slow part, for reruns)::

    .venv/bin/python benchmarks/segment_ridges.py --data /tmp/seg/data --seeds 1 2 --out OUT.json \
        [--map-cache /tmp/ridge_maps]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch
from scipy import ndimage

from affnerf.data.composite import largest_component
from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import grabcut
from affnerf.predict.segment import mask_iou, resolve_segmenter

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites, seed_sweep_parser  # noqa: E402
from bench_segment import thin_recall  # noqa: E402

#: (radius px, top-hat threshold, reach) of each rule; None = the mask as it ships.
RULES = [None] + [(r, t, reach) for r in (3, 5) for t in (0.1, 0.15, 0.2) for reach in (0.1, 0.2, 0.3)]
#: Share of a piece that must be thin, and the thin-part radius (share of the photo's larger side) that decides it.
THIN_SHARE, THIN_RADIUS = 0.7, 0.0125


def rule_name(rule: tuple | None) -> str:
    return "ships" if rule is None else "radius {} px, top-hat {}, reach {}".format(*rule)


def ridge_map(rgb: np.ndarray, radius: int) -> np.ndarray:
    """(H, W) float32 in [0, 1]: the colour top-hat of an (H, W, 3) uint8 photo with a disc of ``radius`` px.

    Example:
        >>> img = np.zeros((9, 9, 3), np.uint8); img[4, :] = 200
        >>> round(float(ridge_map(img, 2)[4, 4]), 2), float(ridge_map(img, 2)[0, 0])
        (0.78, 0.0)
    """
    img = rgb.astype(np.float32) / 255
    disc = np.hypot(*np.mgrid[-radius : radius + 1, -radius : radius + 1]) <= radius
    out = np.zeros(img.shape[:2], np.float32)
    for c in range(3):
        ch = img[..., c]
        out = np.maximum(out, ch - ndimage.grey_opening(ch, footprint=disc))
        out = np.maximum(out, ndimage.grey_closing(ch, footprint=disc) - ch)
    return out


def ridges_touching(ridges: np.ndarray, mask: np.ndarray, reach: float) -> np.ndarray:
    """(H, W) bool: the 8-connected pieces of the (H, W) bool ``ridges`` outside ``mask`` within ``reach`` of the
    image's larger side of it that touch it, are at least :data:`THIN_SHARE` thin and no larger than it."""
    near = ndimage.distance_transform_edt(~mask) <= reach * max(mask.shape)
    found = ridges & near & ~mask
    labels, count = ndimage.label(found, structure=np.ones((3, 3)))
    if count == 0:
        return np.zeros_like(mask)
    index = np.arange(1, count + 1)
    touching = np.zeros(count + 1, bool)
    touching[np.unique(labels[ndimage.binary_dilation(mask, iterations=2) & (labels > 0)])] = True
    size = ndimage.sum(found, labels, index)
    thin = ndimage.sum(grabcut.thin_parts(found, THIN_RADIUS), labels, index) / np.maximum(size, 1)
    keep = np.zeros(count + 1, bool)
    keep[1:] = touching[1:] & (thin >= THIN_SHARE) & (size <= mask.sum())
    return keep[labels]


def rule_mask(rgb: np.ndarray, prob: np.ndarray, mask: np.ndarray, rule: tuple | None, maps: dict) -> np.ndarray:
    """``auto``'s redrawn mask, with ``rule``'s ridges made "probably object" in its trimap (``maps``: the photo's
    ridge maps by radius, filled on first use)."""
    if not mask.any():
        return mask
    if rule is None:
        return grabcut.refine_with_grabcut(rgb, mask, prob)
    radius, threshold, reach = rule
    if radius not in maps:
        maps[radius] = ridge_map(rgb, radius)
    labels = grabcut.probability_trimap(prob, mask)
    labels[ridges_touching(maps[radius] >= threshold, mask, reach) & (labels == 0)] = 3  # GC_BGD -> GC_PR_FGD
    return largest_component(grabcut.grabcut_labels(rgb, labels))


def photo_map(model, rgb: np.ndarray, cache: Path | None) -> np.ndarray:
    """The segmenter's probability map of ``rgb``, read from or written to ``cache`` (a .npy path) when given."""
    if cache is not None and cache.is_file():
        return np.load(cache)
    prob = segnet.photo_probability(model, rgb)
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        np.save(cache, prob)
    return prob


def seed_result(data: Path, seed: int, count: int, model, map_cache: Path | None) -> dict:
    rows = []
    for c in bench_composites(data, seed, count):
        prob = photo_map(model, c.rgb, None if map_cache is None else map_cache / f"seed{seed}" / f"{c.index}.npy")
        mask, maps = segnet.probability_mask(prob), {}
        row = {"index": c.index, "object": c.obj.record.object_id, "background": c.background}
        for rule in RULES:
            found = rule_mask(c.rgb, prob, mask, rule, maps)
            row[rule_name(rule)] = {"iou": round(mask_iou(found, c.truth), 4), "thin": thin_recall(found, c.truth)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    summary = {}
    for name in map(rule_name, RULES):
        thin = [r[name]["thin"] for r in rows if r[name]["thin"] is not None]
        ious = np.array([r[name]["iou"] for r in rows])
        summary[name] = {"mean_iou": round(float(ious.mean()), 4), "thin_recall": round(float(np.mean(thin)), 4),
                         "share_at_0.9": round(float((ious >= 0.9).mean()), 3)}  # fmt: skip
    return {"summary": summary, "per_composite": rows}


def main() -> None:
    parser = seed_sweep_parser(__doc__)
    parser.add_argument("--map-cache", type=Path, default=None, help="folder keeping the probability maps")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    model = segnet.load_segmenter(resolve_segmenter(None))
    result = {"machine": describe_machine(), "rules": [rule_name(r) for r in RULES], "seeds": {}}
    for seed in args.seeds:
        result["seeds"][str(seed)] = seed_result(args.data, seed, args.composites, model, args.map_cache)
        args.out.write_text(json.dumps(result, indent=1))
    print(json.dumps({s: v["summary"] for s, v in result["seeds"].items()}, indent=1))


if __name__ == "__main__":
    main()
