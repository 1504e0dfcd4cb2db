"""Can a scorer pick the object among several candidate masks of a cluttered photo? (issue 16; tried, not kept)

On the composite benchmark (``bench_segment.py``) the salient model and GrabCut both go for the photograph's own
subject (the astronaut, the coffee cup) and `auto` reaches a mean mask IoU of 0.54. Yet the salient map often holds
the pasted object too, as a second region. This measures the ceiling and the reach of choosing among candidates:

- candidates of a photo: the four largest connected regions of the salient map at each of the thresholds 0.5, 0.3
  and 0.15, each also redrawn by ``predict --box``'s separation in its bounding box loosened by 10 % a side, and
  GrabCut from the centred rectangle (near-duplicates, IoU > 0.95, dropped);
- what a candidate is described by: its area, border contact, mean saliency inside and outside, fill of its box,
  the box's size and place, and (``codes``) the shipped model's 64 code values of its crop, the crop ``predict``
  would encode: the encoders know the object families, so a crop of a coffee cup should code unlike a bottle;
- the scorer: a linear model or a 32-unit MLP predicting the candidate's IoU with the true mask (cross-entropy on
  the IoU), trained on composites of the training split's objects pasted onto scikit-image photographs *other* than
  the benchmark's six and onto dead-leaves clutter (``affnerf.data.composite``), then applied to the benchmark's
  composites (seeds given), where the highest-scoring candidate is the mask.

Run::

    .venv/bin/python benchmarks/segment_proposals.py --train-data /tmp/w/data --data /tmp/seg/data --seeds 0 1

Writes ``benchmarks/results/segment_proposals.json`` and prints the table of ``segment_proposals.md``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch
from bench_composites import BACKGROUNDS, backgrounds, composite
from scipy import ndimage

from affnerf.data import composite as synth
from affnerf.data.crop import crop_object, object_bbox
from affnerf.data.dataset import Dataset
from affnerf.environment import describe_machine
from affnerf.predict import grabcut, salient, segment
from affnerf.predict.predictor import Predictor
from affnerf.predict.shipped import shipped_model

THRESHOLDS = (0.5, 0.3, 0.15)
MIN_AREA = 0.003  # share of the photo


def candidates(rgb: np.ndarray, prob: np.ndarray) -> list[np.ndarray]:
    """(H, W) bool candidate masks of an (H, W, 3) photo with (H, W) saliency ``prob`` (see the module's notes)."""
    h, w = prob.shape
    out: list[np.ndarray] = []

    def add(mask: np.ndarray) -> None:
        if mask.sum() >= MIN_AREA * h * w and all(segment.mask_iou(o, mask) <= 0.95 for o in out):
            out.append(mask)

    for t in THRESHOLDS:
        labels, count = ndimage.label(prob > t, structure=np.ones((3, 3)))
        sizes = ndimage.sum(np.ones_like(prob), labels, index=np.arange(1, count + 1))
        for i in np.argsort(-sizes)[:4]:
            region = labels == i + 1
            add(region)
            x0, y0, x1, y1 = object_bbox(region)
            bw, bh = x1 - x0, y1 - y0
            box = (int(x0 - 0.1 * bw), int(y0 - 0.1 * bh), int(x1 + 0.1 * bw), int(y1 + 0.1 * bh))
            if min(box[2] - box[0], box[3] - box[1]) >= segment.MIN_BOX_SIDE:
                add(segment.segment(rgb, "auto", "composite", None, box).mask)
    add(grabcut.grabcut_mask(rgb))
    return out


def describe(prob: np.ndarray, mask: np.ndarray) -> list[float]:
    """The 10 hand-made features of one candidate (see the module's notes)."""
    h, w = mask.shape
    x0, y0, x1, y1 = object_bbox(mask)
    border = np.ones_like(mask)
    border[3:-3, 3:-3] = False
    edges_touched = int(x0 <= 2) + int(y0 <= 2) + int(x1 >= w - 2) + int(y1 >= h - 2)
    return [
        mask.mean(), (mask & border).sum() / border.sum(), edges_touched, float(prob[mask].mean()),
        float(prob[~mask].mean()), mask.sum() / ((x1 - x0) * (y1 - y0)), (x1 - x0) / w, (y1 - y0) / h,
        (x0 + x1) / 2 / w - 0.5, (y0 + y1) / 2 / h - 0.5,
    ]  # fmt: skip


def table(photos, predictor: Predictor, saliency) -> list[dict]:
    """Per photo (category, background, rgb, truth): its candidates' IoU, features and codes."""
    size, bg = predictor.loaded.model.config.encoder_resolution, predictor.loaded.background
    rows = []
    for category, where, rgb, truth in photos:
        prob = saliency.saliency(rgb)
        masks = candidates(rgb, prob)
        codes = np.zeros((0, 64), np.float32)
        if masks:
            c = predictor.encode_crops(np.stack([crop_object(rgb, m, size, bg) for m in masks]))
            codes = torch.cat([c.shape, c.appearance], 1).numpy()
        rows.append({"category": category, "background": where, "iou": [segment.mask_iou(m, truth) for m in masks],
                     "features": [describe(prob, m) for m in masks], "codes": list(codes)})  # fmt: skip
    return rows


def training_photos(data: Path, count: int, seed: int):
    """Composites of the training split's objects on non-benchmark photographs and clutter."""
    rng, ds = np.random.default_rng(seed), Dataset.open(data)
    entries, library = ds.objects("train"), synth.photo_library()
    for _ in range(count):
        obj = ds.load_object(entries[rng.integers(len(entries))])
        view = int(rng.integers(len(obj.record.frames)))
        cut = synth.cut_to_box(obj.rgb(view), obj.affordance(view) > 0)
        rgb, alpha = synth.paste(rng, synth.random_background(rng, (400, 300), library), cut, scale=(0.35, 0.7))
        yield obj.record.category, "training", rgb, alpha > 0.5


def benchmark_photos(data: Path, seed: int, count: int = 48):
    """The composites of ``bench_segment.py --seed SEED`` (same draws, same order)."""
    rng, ds, bgs = np.random.default_rng(seed), Dataset.open(data), backgrounds()
    entries = ds.objects()
    for k, idx in enumerate(rng.permutation(len(entries))[:count]):
        obj = ds.load_object(entries[idx])
        view = int(rng.integers(len(obj.record.frames)))
        name = BACKGROUNDS[k % len(BACKGROUNDS)]
        rgb, truth = composite(obj.rgb(view), obj.affordance(view) > 0, bgs[name], bool(k % 2), rng)
        yield obj.record.category, name, rgb, truth


def design(rows: list[dict], codes: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(N, F) inputs, (N,) IoU targets and (N,) photo index of every candidate."""
    x, y, g = [], [], []
    for i, row in enumerate(rows):
        for k, iou in enumerate(row["iou"]):
            x.append(list(row["features"][k]) + (list(row["codes"][k]) if codes else []))
            y.append(iou)
            g.append(i)
    return np.array(x, np.float32), np.array(y, np.float32), np.array(g)


def fit_scorer(x: np.ndarray, y: np.ndarray, hidden: int, steps: int = 1500):
    """A linear model (``hidden`` = 0) or one-hidden-layer MLP from standardised inputs to the IoU's logit."""
    torch.manual_seed(0)
    mu, sd = x.mean(0), x.std(0) + 1e-6
    net = torch.nn.Linear(x.shape[1], 1) if hidden == 0 else torch.nn.Sequential(
        torch.nn.Linear(x.shape[1], hidden), torch.nn.ReLU(), torch.nn.Linear(hidden, 1))  # fmt: skip
    opt = torch.optim.Adam(net.parameters(), 1e-2 if hidden == 0 else 3e-3, weight_decay=1e-3)
    xt, yt = torch.tensor((x - mu) / sd), torch.tensor(y)
    for _ in range(steps):
        opt.zero_grad()
        torch.nn.functional.binary_cross_entropy_with_logits(net(xt)[:, 0], yt).backward()
        opt.step()
    return lambda a: net(torch.tensor((a - mu) / sd))[:, 0].detach().numpy()


def chosen(rows: list[dict], scorer, codes: bool) -> tuple[list[float], list[float]]:
    """Per photo, the IoU of the best-scoring candidate and of the best candidate (0 without candidates)."""
    x, y, g = design(rows, codes)
    score = scorer(x) if len(x) else np.zeros(0)
    picked = [float(y[g == i][np.argmax(score[g == i])]) if (g == i).any() else 0.0 for i in range(len(rows))]
    best = [float(y[g == i].max()) if (g == i).any() else 0.0 for i in range(len(rows))]
    return picked, best


def summary(rows: list[dict], scorer, codes: bool, per_background: bool) -> dict:
    """Mean IoU of the chosen and of the best candidates (and of the chosen per background photograph)."""
    picked, best = chosen(rows, scorer, codes)
    out = {"chosen": round(float(np.mean(picked)), 4), "best candidate": round(float(np.mean(best)), 4)}
    if per_background:
        out["per background"] = {
            b: round(float(np.mean([p for p, r in zip(picked, rows, strict=True) if r["background"] == b])), 3)
            for b in BACKGROUNDS
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--train-data", type=Path, default=Path("/tmp/w/data"))
    parser.add_argument("--data", type=Path, default=Path("/tmp/seg/data"))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--training-photos", type=int, default=400)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "segment_proposals.json")
    args = parser.parse_args()
    predictor = Predictor.load(shipped_model(), "cpu")
    saliency = salient.load_salient_model()
    train = table(training_photos(args.train_data, args.training_photos, 100), predictor, saliency)
    tests = {s: table(benchmark_photos(args.data, s), predictor, saliency) for s in args.seeds}
    result: dict = {"benchmark": "segment_proposals", "machine": describe_machine(), "settings": vars(args) | {
        "train_data": str(args.train_data), "data": str(args.data), "out": str(args.out)}, "rows": []}  # fmt: skip
    for codes in (False, True):
        for hidden in (0, 32):
            scorer = fit_scorer(*design(train, codes)[:2], hidden)
            row = {"codes": codes, "hidden": hidden}
            for name, rows in {"training": train, **{f"seed {s}": r for s, r in tests.items()}}.items():
                row[name] = summary(rows, scorer, codes, per_background=name != "training")
            result["rows"].append(row)
            print(json.dumps(row))
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
