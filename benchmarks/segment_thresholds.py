"""The segmenter mask's constants, re-chosen on the map that ships (issue 16). The hysteresis thresholds (0.4 / 0.5)
were chosen on the whole photo's map, before the tiles; the map ``predict`` reads now is, per pixel, the larger of
the whole photo's and the tiles' (:func:`affnerf.model.segmenter.photo_probability`), a map biased upward, so a
higher pair may now fit it better. GrabCut's probability trimap (band 0.06, sure background below 0.05) was chosen
before the tiles too. Computing the map is the costly part (about 8 s a composite on one thread), so this script
works in two steps:

- ``cache``: for each composite of the composite benchmark's seeds (``bench_composites.py``) it saves the
  composite, its true mask and the shipped map (``.npz`` per composite, float32 as ``predict`` sees it);
- ``sweep``: for each variant (hysteresis pair; trimap band, sure-background level and, new, a probability from
  which the mask's pixels, or only its thin parts, are sure object, so that GrabCut cannot drop a thin part the map
  is sure of) it scores, on the cached maps, the mask ``auto`` would make
  (:func:`affnerf.model.segmenter.probability_mask`, redrawn by :func:`affnerf.predict.grabcut.probability_trimap`
  and GrabCut) against the true mask. The first variant of each set is ``auto``'s segmenter mask before the sure
  thin parts (as of 2026-12-03); ``--set thin``'s "sure object from 0.8 on parts thinner than radius 0.0125" is
  ``auto``'s now.

Run (one thread a process; choose on seeds 1 and 2, check on the others)::

    .venv/bin/python benchmarks/segment_thresholds.py cache --data /tmp/seg/data --seeds 0 1 2 3 --cache /tmp/maps
    .venv/bin/python benchmarks/segment_thresholds.py sweep --cache /tmp/maps --seeds 0 1 2 3 --out sweep.json
    .venv/bin/python benchmarks/segment_thresholds.py sweep --set sure-object --cache /tmp/maps --seeds 0 1 --out s.json
    .venv/bin/python benchmarks/segment_thresholds.py sweep --set thin --cache /tmp/maps --seeds 0 1 --out thin.json
    .venv/bin/python benchmarks/segment_thresholds.py report sweep.json --choose 1 2
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch

from affnerf.data.composite import largest_component
from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import grabcut, shipped
from affnerf.predict.segment import mask_iou

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import bench_composites  # noqa: E402

#: The shipped hysteresis (low, high), and the probability trimap (band, sure background, sure object, thin radius)
#: before the sure thin parts: every sweep's baseline.
SHIPPED = (segnet.SEGMENTER_LOW_THRESHOLD, segnet.SEGMENTER_THRESHOLD)
BEFORE_TRIMAP = (grabcut.PROBABILITY_TRIMAP_BAND, grabcut.PROBABILITY_SURE_BACKGROUND, None, None)
#: Hysteresis pairs tried with the trimap before, and trimaps tried with the shipped pair (``--set main``).
PAIRS = [(0.3, 0.5), (0.4, 0.6), (0.5, 0.6), (0.5, 0.7), (0.6, 0.7), (0.6, 0.8)]
TRIMAPS = [
    (0.04, 0.05, None, None),
    (0.09, 0.05, None, None),
    (0.06, 0.02, None, None),
    (0.06, 0.1, None, None),
    (0.06, 0.05, 0.9, None),
    (0.06, 0.05, 0.95, None),
    (0.06, 0.05, 0.98, None),
]
#: The second sweep (``--set sure-object``), around the first sweep's best: lower sure-object levels, and 0.9 with
#: the band moved.
SURE_OBJECT_TRIMAPS = [
    (0.06, 0.05, 0.7, None),
    (0.06, 0.05, 0.8, None),
    (0.06, 0.05, 0.85, None),
    (0.06, 0.05, 0.9, None),
    (0.04, 0.05, 0.9, None),
    (0.09, 0.05, 0.9, None),
]
#: The third (``--set thin``): sure object only on the mask's thin parts (radius 3, 5 and 8 px at 400 px).
THIN_TRIMAPS = [(0.06, 0.05, so, r) for r in (0.0075, 0.0125, 0.02) for so in (0.8, 0.9)]
SETS = {"main": TRIMAPS, "sure-object": SURE_OBJECT_TRIMAPS, "thin": THIN_TRIMAPS}


def variant_name(pair: tuple[float, float], trimap: tuple) -> str:
    name = f"hysteresis {pair[0]}/{pair[1]}, band {trimap[0]}, sure background below {trimap[1]}"
    if trimap[2] is None:
        return name
    name = f"{name}, sure object from {trimap[2]}"
    return name if trimap[3] is None else f"{name} on parts thinner than radius {trimap[3]}"


def variants(which: str = "main") -> dict[str, tuple[tuple[float, float], tuple]]:
    """Every variant of the set ``which`` (:data:`SETS`) by name, the trimap before the sure thin parts first."""
    grid = [(SHIPPED, BEFORE_TRIMAP)] + [(SHIPPED, t) for t in SETS[which]]
    if which == "main":
        grid[1:1] = [(p, BEFORE_TRIMAP) for p in PAIRS]
    return {variant_name(p, t): (p, t) for p, t in grid}


def cache(args: argparse.Namespace) -> None:
    """Saves each composite of each seed with its true mask and the shipped map under ``args.cache``."""
    torch.set_num_threads(args.threads)
    model = segnet.read_segmenter(shipped.shipped_segmenter())
    args.cache.mkdir(parents=True, exist_ok=True)
    for seed in args.seeds:
        for c in bench_composites(args.data, seed, args.composites):
            path = args.cache / f"seed{seed}_{c.index:03d}.npz"
            if path.exists():
                continue
            start = time.perf_counter()
            prob = segnet.photo_probability(model, c.rgb)
            secs = time.perf_counter() - start
            np.savez_compressed(path, rgb=c.rgb, truth=c.truth, prob=prob, object=c.obj.record.object_id,
                                background=c.background, shadow=c.shadow, seconds=secs)  # fmt: skip
            print(path.name, round(secs, 2), flush=True)


def redrawn_iou(rgb: np.ndarray, truth: np.ndarray, prob: np.ndarray, pair, trimap) -> tuple[float, float]:
    """IoU with ``truth`` of the mask of ``prob`` at the hysteresis ``pair`` and of it redrawn by GrabCut with the
    probability ``trimap`` (band, sure background, sure object, thin radius), as ``auto`` does it."""
    mask = segnet.probability_mask(prob, thresholds=pair)
    if not mask.any():
        return 0.0, 0.0
    labels = grabcut.probability_trimap(prob, mask, *trimap)
    return mask_iou(mask, truth), mask_iou(largest_component(grabcut.grabcut_labels(rgb, labels)), truth)


def sweep_seed(cache_dir: Path, seed: int, which: str) -> list[dict]:
    """Per cached composite of ``seed``: each variant's (network mask IoU, redrawn IoU)."""
    rows, grid = [], variants(which)
    for path in sorted(cache_dir.glob(f"seed{seed}_*.npz")):
        z = np.load(path)
        rgb, truth, prob = z["rgb"], z["truth"], z["prob"]
        row = {"composite": path.stem, "object": str(z["object"]), "background": str(z["background"])}
        row["scores"] = {n: [round(v, 4) for v in redrawn_iou(rgb, truth, prob, p, t)] for n, (p, t) in grid.items()}
        rows.append(row)
        print(path.stem, round(row["scores"][next(iter(grid))][1], 3), flush=True)
    return rows


def seed_means(rows: list[dict]) -> dict:
    """Per variant: mean network-mask IoU, mean redrawn IoU and the redrawn share ≥ 0.9."""
    out = {}
    for name in rows[0]["scores"]:
        net, red = np.array([r["scores"][name] for r in rows]).T
        out[name] = {"network": round(float(net.mean()), 4), "redrawn": round(float(red.mean()), 4),
                     "redrawn_share_0.9": round(float((red >= 0.9).mean()), 4)}  # fmt: skip
    return out


def sweep(args: argparse.Namespace) -> None:
    """Scores every variant on the cached seeds and writes their per-seed means and per-composite IoUs."""
    result = {"machine": describe_machine(), "variants": list(variants(args.set)), "seeds": {}}
    for seed in args.seeds:
        rows = sweep_seed(args.cache, seed, args.set)
        result["seeds"][str(seed)] = {"means": seed_means(rows), "composites": rows}
        args.out.write_text(json.dumps(result, separators=(",", ":")) + "\n")  # compact: 14 variants a composite


def report(args: argparse.Namespace) -> None:
    """Prints a markdown table of the sweeps' redrawn mean IoU per variant: the choice seeds, each check seed, and
    over the check seeds' composites the mean and the share ≥ 0.9."""
    seeds = {}
    for path in args.sweeps:
        seeds.update(json.loads(path.read_text())["seeds"])
    names, check = list(seeds[str(args.choose[0])]["means"]), [str(s) for s in seeds if int(s) not in args.choose]
    order = [*map(str, args.choose), *check]
    print("| variant | " + " | ".join(f"seed {s}" for s in order) + " | check mean | ≥ 0.9 |")
    print("| --- " * (len(args.choose) + len(check) + 3) + "|")
    for name in names:
        per = [seeds[s]["means"][name]["redrawn"] for s in order]
        reds = [sc[name][1] for s in check for sc in (r["scores"] for r in seeds[s]["composites"])]
        cells = " | ".join(f"{v:.3f}" for v in per)
        print(f"| {name} | {cells} | {np.mean(reds):.4f} | {np.mean(np.array(reds) >= 0.9):.0%} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="step", required=True)
    c = sub.add_parser("cache", help="compute and save the shipped map of each composite")
    c.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    c.add_argument("--composites", type=int, default=48)
    c.add_argument("--threads", type=int, default=1)
    s = sub.add_parser("sweep", help="score every variant on the cached maps")
    s.add_argument("--out", type=Path, required=True)
    s.add_argument("--set", choices=list(SETS), default="main", help="which variants")
    for p in (c, s):
        p.add_argument("--seeds", type=int, nargs="+", default=[0])
        p.add_argument("--cache", type=Path, required=True)
    r = sub.add_parser("report", help="a markdown table of sweeps' JSONs")
    r.add_argument("sweeps", type=Path, nargs="+")
    r.add_argument("--choose", type=int, nargs="+", default=[1, 2], help="the seeds the choice is made on")
    args = parser.parse_args()
    {"cache": cache, "sweep": sweep, "report": report}[args.step](args)


if __name__ == "__main__":
    main()
