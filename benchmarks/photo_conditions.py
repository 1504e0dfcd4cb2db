"""Lighting and camera quality: how much a prediction from one photo loses when the photo is not a clean render.

Each test object's input view (the Table 2 protocol's choice) is changed as a real photo would be: darker or
brighter exposure, a warm or a cool light (per-channel gains), lower contrast, a blurred and noisy camera, heavy
JPEG compression. Each version is predicted as ``affnerf predict`` does (cropped, encoded, fitted to the photo for
``--fit-steps``), with the object's true mask as the photo's alpha channel so that only the model's response to the
light is measured, not the separation's (``bench_segment.py`` measures that), and the affordance mIoU at the
object's target views (the clean ground truth) and the F-score at 1 cm of its mesh are compared with the clean
photo's. The shipped model was trained on clean renders without input jitter (its training config's ``input_jitter``
is 0), so this measures what a user gets from photos with real lighting.

Run::

    affnerf data generate --out /tmp/w/data --objects-per-category 80 --views 30 --seed 0
    .venv/bin/python benchmarks/photo_conditions.py --data /tmp/w/data [--objects 2] [--categories a,b]

Writes ``benchmarks/results/photo_conditions.json`` (``--out``) and its table beside it (``.md``); ``--merge A.json
B.json`` joins the outputs of runs over disjoint categories (two processes side by side) into one.
"""

from __future__ import annotations

import argparse
import io
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from PIL import Image, ImageFilter

from affnerf.data.dataset import Dataset
from affnerf.environment import describe_machine
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.eval.surface import sample_seed, true_samples
from affnerf.predict.predictor import Predictor
from affnerf.predict.shipped import shipped_model

sys.path.insert(0, str(Path(__file__).parent))
from bench_segment import score_photo  # noqa: E402

RESULTS = Path(__file__).parent / "results"


def jpeg(image: np.ndarray, quality: int) -> np.ndarray:
    """The (H, W, 3) uint8 image after a JPEG round trip at ``quality``."""
    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, "JPEG", quality=quality)
    return np.asarray(Image.open(buffer).convert("RGB"))


def blur_and_noise(image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A Gaussian blur of 1.5 px and pixel noise of standard deviation 8 (of 255)."""
    blurred = np.asarray(Image.fromarray(image).filter(ImageFilter.GaussianBlur(1.5)), np.float64)
    return np.clip(np.round(blurred + rng.normal(0, 8, image.shape)), 0, 255).astype(np.uint8)


def scaled(image: np.ndarray, gains: tuple[float, float, float], gamma: float = 1.0) -> np.ndarray:
    """Per-channel gains then a gamma, clipped: exposure and white balance."""
    x = np.clip(image.astype(np.float64) / 255.0 * np.array(gains), 0.0, 1.0) ** gamma
    return np.round(255 * x).astype(np.uint8)


def low_contrast(image: np.ndarray) -> np.ndarray:
    """Contrast halved about mid-grey (a hazy or flat-lit photo)."""
    return np.round(127.5 + 0.5 * (image.astype(np.float64) - 127.5)).astype(np.uint8)


#: The photo conditions: name -> change of an (H, W, 3) uint8 image (``rng`` for the noise).
CONDITIONS = {
    "clean": lambda im, rng: im,
    "dark (exposure x0.5)": lambda im, rng: scaled(im, (0.5, 0.5, 0.5)),
    "bright (exposure x1.4, gamma 0.8)": lambda im, rng: scaled(im, (1.4, 1.4, 1.4), 0.8),
    "warm light (gains 1.15, 1.0, 0.75)": lambda im, rng: scaled(im, (1.15, 1.0, 0.75)),
    "cool light (gains 0.8, 0.95, 1.15)": lambda im, rng: scaled(im, (0.8, 0.95, 1.15)),
    "low contrast (x0.5)": lambda im, rng: low_contrast(im),
    "blur 1.5 px + noise 8/255": blur_and_noise,
    "JPEG quality 25": lambda im, rng: jpeg(im, 25),
}


class LightingCase(NamedTuple):
    """One object's set-up for the lighting changes (:func:`lighting_case`)."""

    view: int  # the input view
    targets: list[int]  # the scored views
    rng: np.random.Generator  # random source of the changes
    truth: Any  # the object's 3D truth, sampled once for every condition
    mask: np.ndarray  # (H, W) bool true object mask of the input view


def lighting_case(obj: Any, protocol: ProtocolConfig) -> LightingCase:
    """An object's input view, target views, random source of the changes, 3D truth and true mask."""
    (view,), targets = choose_views(len(obj), obj.record.object_id, protocol)
    rng = np.random.default_rng(sample_seed(0, obj.record.object_id))
    return LightingCase(view, targets, rng, true_samples(obj, 0), obj.affordance(view) > 0)


def score_lit_photo(
    predictor: Predictor, obj: Any, image: np.ndarray, case: LightingCase, tmp: Path, fit_steps: int
) -> dict[str, float]:
    """Predict the changed (H, W, 3) ``image`` with the ``case``'s true mask as its alpha (lighting only, not
    separation), as ``predict`` does, and score it at the case's target views."""
    photo = tmp / "photo.png"
    Image.fromarray(np.dstack([image, case.mask.astype(np.uint8) * 255])).save(photo)
    return score_photo(predictor, obj, photo, case.targets, fit_steps, case.truth)


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Predict every chosen object under every condition; the per-object scores and the run's settings."""
    ds = Dataset.open(args.data)
    predictor = Predictor.load(Path(shipped_model() if args.checkpoint == "shipped" else args.checkpoint), "cpu")
    protocol = ProtocolConfig(input_views=1, target_views=args.targets, seed=0)
    rows, start = [], time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for category in args.categories.split(","):
            for entry in ds.objects("test", category)[: args.objects]:
                obj = ds.load_object(entry)
                case = lighting_case(obj, protocol)  # the 3D truth once per object, for every condition
                for name, change in CONDITIONS.items():
                    image = change(obj.rgb(case.view), case.rng)
                    scores = score_lit_photo(predictor, obj, image, case, Path(tmp), args.fit_steps)
                    rows.append({"object": obj.record.object_id, "category": category, "condition": name, **scores})
                    print(
                        f"{obj.record.object_id:16s} {name:36s} mIoU {scores['miou']:.3f} F {scores['fscore_1cm']:.3f}"
                    )
    settings = {k: str(v) for k, v in vars(args).items() if k != "merge"}
    return {"settings": settings, "machine": describe_machine(), "seconds": round(time.perf_counter() - start, 1),
            "rows": rows}  # fmt: skip


def table(rows: list[dict]) -> str:
    """Markdown: per condition, mean mIoU and F@1cm over the objects and their change from the clean photo."""
    clean = {r["object"]: r for r in rows if r["condition"] == "clean"}
    lines = ["| photo | mIoU | Δ mIoU | F@1cm | Δ F@1cm | objects |", "| --- | --- | --- | --- | --- | --- |"]
    for name in CONDITIONS:
        sub = [r for r in rows if r["condition"] == name]
        miou, f = np.mean([r["miou"] for r in sub]), np.mean([r["fscore_1cm"] for r in sub])
        dm = np.mean([r["miou"] - clean[r["object"]]["miou"] for r in sub])
        df = np.mean([r["fscore_1cm"] - clean[r["object"]]["fscore_1cm"] for r in sub])
        lines.append(f"| {name} | {miou:.3f} | {dm:+.3f} | {f:.3f} | {df:+.3f} | {len(sub)} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("/tmp/w/data"))
    parser.add_argument("--checkpoint", default="shipped")
    parser.add_argument("--categories", default="bottle,bucket,cabinet,eyeglasses,pen,scissors,screwdriver,teapot")
    parser.add_argument("--objects", type=int, default=2, help="test objects per category")
    parser.add_argument("--targets", type=int, default=5, help="target views per object")
    parser.add_argument("--fit-steps", type=int, default=30)
    parser.add_argument("--out", type=Path, default=RESULTS / "photo_conditions.json")
    parser.add_argument("--merge", type=Path, nargs="*", default=None, help="join these outputs into the table")
    args = parser.parse_args()
    if args.merge:
        parts = [json.loads(p.read_text()) for p in args.merge]
        result = {"parts": [{k: v for k, v in p.items() if k != "rows"} for p in parts],
                  "rows": [r for p in parts for r in p["rows"]]}  # fmt: skip
    else:
        result = run(args)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    text = table(result["rows"])
    args.out.with_suffix(".md").write_text(text + "\n")
    print(text)
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
