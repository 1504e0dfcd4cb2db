"""Silhouette carving of the fitted prediction (issue 12): `affnerf-fit` on the val40 protocol (40 validation
objects, 5 per category, input view 0, 5 target views at 100x75, meshes at 96^3) with the object carved by the
input view's mask at the fitted camera (:mod:`affnerf.predict.carve`), for one margin, or without carving.

    OMP_NUM_THREADS=2 .venv/bin/python benchmarks/silhouette_carving.py --data DATA --margin none|M --out OUT
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import affnerf.eval.methods.affnerf_fit as fit_method
from affnerf.cli.main import main as affnerf_main
from affnerf.predict.shipped import shipped_model

KEYS = ("mIoU", "PA", "MPA", "PSNR", "fscore_1cm", "affordance_miou_3d", "chamfer_l1")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--margin", default="none", help="mask growth as a share of the crop side, or none")
    parser.add_argument("--out", type=Path, required=True)
    a = parser.parse_args()
    margin = None if a.margin == "none" else float(a.margin)
    init = fit_method.FittedAffNeRFMethod.__init__

    def carving_init(self, *args, **kwargs):
        init(self, *args, carve_margin=margin, **kwargs)

    fit_method.FittedAffNeRFMethod.__init__ = carving_init
    args = ["eval", "--run", str(shipped_model()), "--data", str(a.data), "--split", "val", "--method", "affnerf-fit",
            "--scale", "0.25", "--target-views", "5", "--max-objects", "5", "--mesh-resolution", "96", "--device",
            "cpu", "--out", str(a.out)]  # fmt: skip
    code = affnerf_main(args)
    if code:
        raise SystemExit(code)
    mean = json.loads((a.out / "metrics_affnerf-fit.json").read_text())["mean"]
    print(json.dumps({"margin": margin, **{k: mean[k] for k in KEYS if k in mean}}))


if __name__ == "__main__":
    main()
