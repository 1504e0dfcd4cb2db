"""Object separation on cluttered composites: mask IoU and time of each ``--segment`` method.

Rendered objects (a dataset made by ``affnerf data generate``; the true mask is ``affordance > 0``) are pasted at a
random position and scale onto photographs that ship with scikit-image (no download), with or without a soft drop
shadow, and each method's mask is compared with the true one, also with a box around the object (``predict --box``:
the true bounding box loosened by 5-25 % per side, and a tight one loosened by 0-5 %, seeded). ``auto`` uses the
object segmenter (the shipped one, or ``--segmenter FILE``); ``auto (no segmenter)`` is ``auto`` as it was before one
shipped. Also measured: the salient model's and the segmenter's thresholds (sweeps over the same probability maps),
GrabCut's refinement of either mask, how well the segmenter's confidence and the methods' agreement flag a
wrong mask, and the share of the true mask's thin parts that ``auto`` keeps (``auto_thin_recall``: a mask that
drops a screwdriver's shaft keeps an IoU above 0.9, yet the model then predicts another family). These six
photographs are held out of the object segmenter's training
(``affnerf.data.composite.HELD_OUT_BACKGROUNDS``), and the dataset below is made with another seed than the
segmenter's training data, so its objects are new to it too.

Run::

    affnerf data generate --out /tmp/seg/data --objects-per-category 10 --views 4 --seed 7
    .venv/bin/python benchmarks/bench_segment.py --data /tmp/seg/data [--composites 48] [--checkpoint RUN] \
        [--segmenter FILE]    # default: the shipped one; or one from `affnerf train-segmenter`

Writes ``benchmarks/results/segment_composites.json``. With ``--checkpoint`` (a run folder or checkpoint, or
``shipped``), a ``Predictor`` also predicts each object from its composite and from its clean render, and the
affordance mIoU at the object's other dataset views and the 3D F-score at 1 cm of both are reported.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from affnerf.data.dataset import ObjectData
from affnerf.environment import describe_machine
from affnerf.model import segmenter as segnet
from affnerf.predict import grabcut, salient, segment

sys.path.insert(0, str(Path(__file__).parent))
from bench_composites import (  # noqa: E402
    BACKGROUNDS,
    BOX_PADDING,
    CANVAS,
    TIGHT_PADDING,
    bench_composites,
)

THRESHOLDS = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
#: A true mask's thin parts: where a disc of this radius × the canvas's larger side (3 px of 400) does not fit
#: (``grabcut.thin_parts``); objects with fewer than MIN_THIN_PIXELS such pixels are left out of the thin-part recall.
THIN_RADIUS = 0.0075
MIN_THIN_PIXELS = 20


def measure_box(rgb: np.ndarray, truth: np.ndarray, boxes: dict[str, tuple[int, int, int, int]]) -> tuple[dict, dict]:
    """IoU and seconds of ``auto`` and ``salient`` confined to each box around the object (``predict --box``),
    as ``METHOD --box`` + the box's name."""
    iou, secs = {}, {}
    for name, box in boxes.items():
        for method in ("auto", "salient"):
            key = f"{method} --box{name}"
            seg, secs[key] = timed(segment.segment, rgb, method, "composite", None, box)
            iou[key] = segment.mask_iou(seg.mask, truth)
    return iou, secs


def timed(fn, *args) -> tuple[Any, float]:
    start = time.perf_counter()
    out = fn(*args)
    return out, time.perf_counter() - start


def measure_map(
    rgb: np.ndarray,
    truth: np.ndarray,
    name: str,
    probability: Any,
    threshold: float,
    iou: dict,
    secs: dict,
    mask_of: Any = None,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Score a per-pixel object probability (a function of the photo) as method ``name`` and, edges redrawn by
    GrabCut, as ``name+grabcut refine``, into ``iou`` and ``secs``; returns the map, its mask (``mask_of(map)``, by
    default the largest region above ``threshold``) and the threshold sweep (largest region above each)."""
    prob, secs[name] = timed(probability, rgb)
    sweep = {t: segment.mask_iou(segment.largest_component(prob > t), truth) for t in THRESHOLDS}
    mask_of = mask_of or (lambda p: segment.largest_component(p > threshold))
    mask, more = timed(mask_of, prob)
    secs[name] += more
    iou[name] = segment.mask_iou(mask, truth)
    refined, secs[f"{name}+grabcut refine"] = timed(grabcut.refine_with_grabcut, rgb, mask)
    secs[f"{name}+grabcut refine"] += secs[name]
    iou[f"{name}+grabcut refine"] = segment.mask_iou(refined, truth)
    return prob, mask, sweep


def measure_segmenter(
    rgb: np.ndarray, truth: np.ndarray, segmenter, path: Path, boxes: dict
) -> tuple[dict, dict, dict]:
    """IoU and seconds of an object segmenter on one composite (alone, with GrabCut's edges, and alone inside each of
    ``boxes``), its threshold sweep and its confidence."""
    iou, secs = {}, {}
    prob, mask, sweep = measure_map(
        rgb, truth, "segmenter", lambda x: segnet.photo_probability(segmenter, x), segnet.SEGMENTER_THRESHOLD, iou,
        secs, segnet.probability_mask,
    )  # fmt: skip
    for name, box in boxes.items():
        seg, secs[f"segmenter --box{name}"] = timed(segment.segment, rgb, "segmenter", "composite", path, box)
        iou[f"segmenter --box{name}"] = segment.mask_iou(seg.mask, truth)
    return iou, secs, {"segmenter_sweep": sweep, "segmenter_confidence": segnet.mask_confidence(prob, mask)}


def thin_recall(found: np.ndarray, truth: np.ndarray) -> float | None:
    """Share of the true mask's thin parts (``grabcut.thin_parts`` at :data:`THIN_RADIUS`) that the found mask
    covers; None when the object has fewer than :data:`MIN_THIN_PIXELS` such pixels. IoU barely notices a lost shaft;
    this does."""
    thin = grabcut.thin_parts(truth, THIN_RADIUS)
    return None if thin.sum() < MIN_THIN_PIXELS else float((found & thin).sum() / thin.sum())


def measure_one(rgb: np.ndarray, truth: np.ndarray, model, segmenter: Path) -> tuple[dict, dict, dict]:
    """IoU and seconds of each method on one composite (``auto`` with the object segmenter file ``segmenter``, and
    without any, as before one shipped), the salient threshold sweep, and the confidence measures (border
    uniformity; IoU of the salient and GrabCut masks)."""
    iou, secs = {}, {}
    mask, secs["uniform"] = timed(segment.uniform_background_mask, rgb)
    iou["uniform"] = segment.mask_iou(mask, truth)
    rectangle, secs["grabcut"] = timed(grabcut.grabcut_mask, rgb)
    iou["grabcut"] = segment.mask_iou(rectangle, truth)
    _, salient_only, sweep = measure_map(rgb, truth, "salient", model.saliency, salient.SALIENT_THRESHOLD, iou, secs)
    seg, secs["auto"] = timed(segment.segment, rgb, "auto", "composite", segmenter)
    iou["auto"] = segment.mask_iou(seg.mask, truth)
    old, secs["auto (no segmenter)"] = timed(segment.segment, rgb, "auto", "composite", segment.NO_SEGMENTER)
    iou["auto (no segmenter)"] = segment.mask_iou(old.mask, truth)
    extra = {
        "auto_source": seg.source,
        "auto_thin_recall": thin_recall(seg.mask, truth),
        "auto_agreement": old.agreement,
        "border_uniformity": segment.background_uniformity(rgb),
        "agreement_salient_grabcut": segment.mask_iou(salient_only, rectangle),
    }
    return iou, secs, {"sweep": sweep, **extra}


def confidence(rows: list[dict], method: str = "auto", key: str = "auto_agreement", below: float = 0.8) -> dict:
    """How well a low agreement flags a wrong mask: the share of bad masks (IoU < 0.5) flagged, of good ones
    (IoU >= 0.9) flagged by mistake, and the correlation of agreement and IoU."""
    pairs = np.array([(r[key], r["iou"][method]) for r in rows if r[key] is not None])
    if not len(pairs):
        return {}
    a, i = pairs.T
    bad, good = i < 0.5, i >= 0.9
    return {
        "pearson_r": round(float(np.corrcoef(a, i)[0, 1]), 3),
        f"share_of_bad_masks_flagged_below_{below}": round(float((a[bad] < below).mean()), 3) if bad.any() else None,
        f"share_of_good_masks_flagged_below_{below}": round(float((a[good] < below).mean()), 3) if good.any() else None,
        "mean_iou_when_not_flagged": round(float(i[a >= below].mean()), 4) if (a >= below).any() else None,
    }


def summarise(rows: list[dict]) -> dict[str, Any]:
    methods = list(rows[0]["iou"])
    cats = sorted({r["category"] for r in rows})

    def mean(values):
        return round(float(np.mean(values)), 4)

    out: dict[str, Any] = {
        "mask_iou_mean": {m: mean([r["iou"][m] for r in rows]) for m in methods},
        "mask_iou_median": {m: round(float(np.median([r["iou"][m] for r in rows])), 4) for m in methods},
        "share_iou_at_least_0.9": {m: mean([r["iou"][m] >= 0.9 for r in rows]) for m in methods},
        "seconds_per_image_median": {m: round(float(np.median([r["secs"][m] for r in rows])), 4) for m in methods},
        "mask_iou_per_category": {
            c: {m: mean([r["iou"][m] for r in rows if r["category"] == c]) for m in methods} for c in cats
        },  # fmt: skip
    }
    for shadow in (False, True):
        sub = [r for r in rows if r["shadow"] == shadow]
        out[f"mask_iou_mean_{'with' if shadow else 'without'}_shadow"] = {
            m: mean([r["iou"][m] for r in sub]) for m in methods
        }
    thin = [r["auto_thin_recall"] for r in rows if r.get("auto_thin_recall") is not None]
    out["auto_thin_part_recall"] = {"mean": mean(thin) if thin else None, "composites": len(thin),
                                    "radius_px": round(THIN_RADIUS * max(CANVAS))}  # fmt: skip
    out["salient_threshold_sweep"] = {str(t): mean([r["sweep"][t] for r in rows]) for t in THRESHOLDS}
    if "segmenter_sweep" in rows[0]:
        out["segmenter_threshold_sweep"] = {str(t): mean([r["segmenter_sweep"][t] for r in rows]) for t in THRESHOLDS}
    out["confidence_of_auto_without_segmenter_by_agreement"] = confidence(rows, "auto (no segmenter)")
    if "segmenter_confidence" in rows[0]:
        out["confidence_of_segmenter_by_its_confidence"] = confidence(
            rows, "segmenter", "segmenter_confidence", segment.MIN_SEGMENTER_CONFIDENCE
        )
    out["confidence_of_salient_by_agreement_with_grabcut"] = confidence(rows, "salient", "agreement_salient_grabcut")
    return out


def score_photo(
    predictor, obj: ObjectData, photo: Path, targets: list[int], fit_steps: int, truth, box=None, mask=None
) -> dict:
    """The prediction from ``photo`` (separated by the ``mask`` file, or inside ``box``, when given; fitted to it for
    ``fit_steps`` first, as ``affnerf predict`` does; 0 = the encoders' codes): its affordance mIoU at the object's
    ``targets`` views and its F@1cm against ``truth`` (the object's :func:`affnerf.eval.surface.true_samples`)."""
    from affnerf.eval.surface import sample_seed, score_mesh
    from affnerf.metrics.segmentation import confusion_matrix, mean_iou
    from affnerf.predict.invert import InversionConfig

    enc = predictor.encode_image(photo, mask=mask, box=box)
    if fit_steps > 0:
        predictor.fit(enc, InversionConfig(steps=fit_steps))
    n = len(predictor.classes)
    conf = sum(confusion_matrix(obj.affordance(i), predictor.render(enc, obj.record.intrinsics, obj.pose(i)).labels, n)
               for i in targets)  # fmt: skip
    surf = score_mesh(predictor.mesh(enc, 96), truth, sample_seed(0, obj.record.object_id))
    return {"miou": mean_iou(conf), "fscore_1cm": surf["fscore_1cm"] if surf else 0.0}


def predictions(checkpoint: str, cases: list[tuple], tmp: Path, fit_steps: int) -> dict[str, Any]:
    """mIoU at the other dataset views and F@1cm of predictions from the composite (with no flags, and with
    ``--box``) and from the clean render (:func:`score_photo`); ``cases``: (object, view, composite, box)."""
    from affnerf.eval.surface import true_samples
    from affnerf.predict.predictor import Predictor
    from affnerf.predict.shipped import shipped_model

    predictor = Predictor.load(Path(shipped_model() if checkpoint == "shipped" else checkpoint), "auto")
    kinds = ("composite", "composite --box", "clean")
    scores: dict[str, dict[str, list[float]]] = {k: {"miou": [], "fscore_1cm": []} for k in kinds}
    per_case: list[dict[str, Any]] = []
    for k, (obj, view, comp, box) in enumerate(cases):
        photo, clean = tmp / f"c{k}.png", tmp / f"r{k}.png"
        Image.fromarray(comp).save(photo)
        Image.fromarray(obj.rgb(view)).save(clean)
        others = [i for i in range(len(obj.record.frames)) if i != view]
        truth = true_samples(obj, 0)
        per_case.append({"object": obj.record.object_id})
        for kind, path, kind_box in zip(kinds, (photo, photo, clean), (None, box, None), strict=True):
            for metric, value in score_photo(predictor, obj, path, others, fit_steps, truth, kind_box).items():
                scores[kind][metric].append(value)
                per_case[-1][f"{kind} {metric}"] = round(float(value), 4)
    return {
        "checkpoint": checkpoint,
        "fit_steps": fit_steps,
        "objects": len(cases),
        **{kind: {m: round(float(np.mean(v)), 4) for m, v in s.items()} for kind, s in scores.items()},
        "per_composite": per_case,
    }


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--composites", type=int, default=48)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--checkpoint", "--run", default=None, help="also score predictions (a run, or 'shipped')")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "segment_composites.json")
    parser.add_argument(
        "--segmenter", type=Path, default=None, help="an object segmenter file (default: the shipped one)"
    )
    parser.add_argument("--fit-steps", type=int, default=30, help="predictions: fit to the photo (0 = off)")
    return parser.parse_args()


def settings(args: argparse.Namespace, composites: int) -> dict[str, Any]:
    """The run's settings, as recorded with its results."""
    return {
        "data": str(args.data),
        "composites": composites,
        "seed": args.seed,
        "canvas": CANVAS,
        "backgrounds": BACKGROUNDS,
        "salient_threshold": salient.SALIENT_THRESHOLD,
        "auto_uniformity": segment.AUTO_UNIFORMITY,
        "refine_salient": segment.REFINE_SALIENT,
        "segmenter": str(args.segmenter),
        "segmenter_threshold": segnet.SEGMENTER_THRESHOLD,
        "segmenter_low_threshold": segnet.SEGMENTER_LOW_THRESHOLD,
        "segmenter_extra": [segnet.SEGMENTER_EXTRA_CONFIDENCE, segnet.SEGMENTER_EXTRA_SIZE],
        "segmenter_main_region": [segnet.SEGMENTER_REGION_SURENESS_POWER, segnet.SEGMENTER_MAIN_MIN_SIZE],
        "onnx_threads": salient.SESSION_THREADS,
        "box_padding": BOX_PADDING,
        "tight_box_padding": TIGHT_PADDING,
        "box_margin": segment.BOX_MARGIN,
        "segmenter_tile_share": segnet.SEGMENTER_TILE_SHARE,
    }


def main() -> None:
    args = parse_args()
    args.segmenter = args.segmenter or segment.resolve_segmenter(None)
    model = salient.load_salient_model()
    model.saliency(np.zeros((32, 32, 3), np.uint8))  # warm-up: the first run pays one-off allocations
    segmenter = segnet.load_segmenter(args.segmenter)
    segnet.object_probability(segmenter, np.zeros((32, 32, 3), np.uint8))
    rows, cases = [], []
    for c in bench_composites(args.data, args.seed, args.composites):
        obj, rgb, truth, box, k, bg, shadow = c.obj, c.rgb, c.truth, c.box, c.index, c.background, c.shadow
        iou, secs, extra = measure_one(rgb, truth, model, args.segmenter)
        boxes = {"": box, " (tight)": c.tight_box}
        boxed = measure_box(rgb, truth, boxes)
        iou, secs = {**iou, **boxed[0]}, {**secs, **boxed[1]}
        more = measure_segmenter(rgb, truth, segmenter, args.segmenter, boxes)
        iou, secs, extra = {**iou, **more[0]}, {**secs, **more[1]}, {**extra, **more[2]}
        rows.append({"object": obj.record.object_id, "category": obj.record.category, "background": bg,
                     "shadow": shadow, "box": box, "iou": iou, "secs": secs, **extra})  # fmt: skip
        cases.append((obj, c.view, rgb, box))
        print(f"{k:3d} {obj.record.object_id:16s} {bg:22s} shadow={shadow!s:5s} "
              + " ".join(f"{m}={v:.3f}" for m, v in iou.items()))  # fmt: skip
    result = {
        "benchmark": "segment_composites",
        "settings": settings(args, len(rows)),
        "machine": describe_machine(),
        **summarise(rows),
        "composites": [{k: v for k, v in r.items() if not k.endswith("sweep")} for r in rows],
    }
    if args.checkpoint:
        with tempfile.TemporaryDirectory() as tmp:
            result["prediction"] = predictions(args.checkpoint, cases, Path(tmp), args.fit_steps)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    for key in ("mask_iou_mean", "seconds_per_image_median", "salient_threshold_sweep"):
        print(key, result[key])
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
