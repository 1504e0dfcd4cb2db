"""Does a clipped-colour share tell which overexposed photos the model gets wrong? A hold-out check.

On the 16 objects of ``photo_conditions.py`` (the first two test objects per category), the photos made 1.4 times too
bright whose object clips a colour channel (>= 250 of 255) in over a quarter of its pixels were the ones that lost
most. This scores the next three test objects of each category (indices 2-4, 24 objects no rule was chosen on) clean
and overexposed, as ``photo_conditions.py`` does (true mask as alpha, fitted as ``predict`` does), with each
overexposed photo's clipped share, so that the rule can be tested where it was not found.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/overexposure_holdout.py --data DATA --categories a,b --out a.json
    .venv/bin/python benchmarks/overexposure_holdout.py --merge a.json b.json   # -> results/overexposure_holdout.json
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from photo_conditions import CONDITIONS, lighting_case, score_lit_photo

from affnerf.data.dataset import Dataset
from affnerf.environment import describe_machine
from affnerf.eval.protocol import ProtocolConfig
from affnerf.predict.predictor import Predictor
from affnerf.predict.shipped import shipped_model

BRIGHT = "bright (exposure x1.4, gamma 0.8)"
#: The rule under test: a channel at or above this level is clipped; over SHARE of the object's pixels, "overexposed".
LEVEL, SHARE = 250, 0.25


def clipped_share(rgb: np.ndarray, mask: np.ndarray) -> float:
    """Share of the (H, W) ``mask``'s pixels of the (H, W, 3) uint8 ``rgb`` with a channel at or above LEVEL."""
    return float((rgb[mask] >= LEVEL).any(axis=-1).mean())


def score_object(predictor: Predictor, obj: Any, tmp: Path) -> dict[str, Any]:
    """The object's clean and overexposed mIoU and the overexposed photo's clipped share."""
    case = lighting_case(obj, ProtocolConfig(1, 5, seed=0))
    row: dict[str, Any] = {"object": obj.record.object_id}
    for name in ("clean", BRIGHT):
        image = CONDITIONS[name](obj.rgb(case.view), case.rng)
        row["clean" if name == "clean" else "bright"] = score_lit_photo(predictor, obj, image, case, tmp, 30)["miou"]
    row["clipped_share"] = clipped_share(image, case.mask)  # of the overexposed photo, the last drawn
    return row


def summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Mean mIoU change above and below the rule's share, and how many lost more than 0.1 on each side."""
    sides = {
        "above": [r for r in rows if r["clipped_share"] > SHARE],
        "below": [r for r in rows if r["clipped_share"] <= SHARE],
    }
    return {
        side: {
            "objects": len(group),
            "mean_miou_change": round(statistics.mean(r["bright"] - r["clean"] for r in group), 4) if group else None,
            "lost_over_0.1": sum(r["bright"] - r["clean"] < -0.1 for r in group),
        }
        for side, group in sides.items()
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path)
    parser.add_argument("--categories", default="bottle,bucket,cabinet,eyeglasses,pen,scissors,screwdriver,teapot")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/overexposure_holdout.json"))
    parser.add_argument("--merge", nargs="*", type=Path)
    args = parser.parse_args()
    if args.merge:
        parts = [json.loads(p.read_text()) for p in args.merge]
        rows = [r for p in parts for r in p["rows"]]
        result = {"settings": [p["settings"] for p in parts], "machine": parts[0]["machine"], "rows": rows}
    else:
        ds, predictor = Dataset.open(args.data), Predictor.load(Path(shipped_model()), "cpu")
        with tempfile.TemporaryDirectory() as tmp:
            rows = [score_object(predictor, ds.load_object(e), Path(tmp))
                    for c in args.categories.split(",") for e in ds.objects("test", c)[2:5]]  # fmt: skip
        result = {"settings": {k: str(v) for k, v in vars(args).items()}, "machine": describe_machine(), "rows": rows}
    result["summary"] = summary(result["rows"])
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result["summary"]), "->", args.out)


if __name__ == "__main__":
    main()
