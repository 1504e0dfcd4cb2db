"""Test-time inversion settings, compared on validation objects (issue 12): which fit of the codes to the input
view improves the prediction, and which terms keep the fit from relabelling parts.

Each variant is ``affnerf-fit`` (:mod:`affnerf.predict.invert`) with some :class:`InversionConfig` fields
changed; the first row is the encoder's codes without any fit (``affnerf``). Every variant is scored by the
evaluation protocol on the same objects, input views and target views (conventions §5): by default the first 2
validation objects per category, 1 input view, 5 target views at a quarter of the dataset's resolution, meshes at
96³. Writes ``OUT/inversion_sweep.json`` and ``OUT/inversion_sweep.md``.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/inversion_sweep.py --data DATA \\
        [--run src/affnerf/weights/affnerf-small.pt] [--out benchmarks/results] [--max-objects 2]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from dataclasses import asdict, replace
from pathlib import Path

import torch

from affnerf.data.dataset import Dataset, interleave_categories
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.methods.affnerf_fit import FittedAffNeRFMethod
from affnerf.eval.protocol import ProtocolConfig, evaluate
from affnerf.fileio import write_json_atomic
from affnerf.predict.invert import InversionConfig
from affnerf.predict.loading import load_model
from affnerf.predict.shipped import shipped_model

DEFAULT = InversionConfig()
#: (name, settings changed from the default; None = no fit at all).
VARIANTS: list[tuple[str, dict | None]] = [
    ("encoder's codes, no fit (affnerf)", None),
    ("fit, no affordance terms, prior 1", {"affordance_weight": 0.0, "anchor_points": 0, "prior": 1.0}),
    (
        "fit, affordance on pixels only (weight 1), prior 1",
        {"affordance_weight": 1.0, "anchor_points": 0, "prior": 1.0},
    ),
    ("fit, affordance on pixels only (weight 3), prior 5", {"anchor_points": 0}),
    ("**default**: pixels and 2,048 points (weight 3), prior 5", {}),
    ("default, 60 steps", {"steps": 60}),
    ("default, affordance weight 10", {"affordance_weight": 10.0}),
    ("default, affordance weight 10, prior 2", {"affordance_weight": 10.0, "prior": 2.0}),
    ("default, camera kept where the search put it", {"fit_camera": False}),
    ("default, fitted at 48x48 with 1,024 rays a step", {"resolution": 48, "rays": 1024}),
    ("default, fits from the 2 best cameras, the better kept", {"hypotheses": 2}),
]
KEYS = ("mIoU", "PA", "MPA", "mIoU_object", "PSNR", "fscore_1cm", "affordance_miou_3d")


def run_variant(loaded, settings: dict | None, objects, protocol: ProtocolConfig, classes: int, mesh_res: int):
    """The protocol's mean metrics of one variant and its wall time."""
    if settings is None:
        method = ConditionedNeRFMethod(loaded, mesh_resolution=mesh_res)
    else:
        method = FittedAffNeRFMethod(loaded, mesh_resolution=mesh_res, inversion=replace(DEFAULT, **settings))
    started = time.perf_counter()
    result = evaluate(method, objects, protocol, "val", classes, 0).to_json()
    return result["mean"], time.perf_counter() - started


def markdown(rows: list[dict], header: str) -> str:
    lines = [header, "", "| variant | mIoU | PA | MPA | mIoU object | PSNR | F@1cm | 3D aff. mIoU | s / object |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    for row in rows:
        cells = [f"{row['mean'][k]:.3f}" if k != "PSNR" else f"{row['mean'][k]:.2f}" for k in KEYS]
        lines.append(f"| {row['name']} | " + " | ".join(cells) + f" | {row['seconds_per_object']:.1f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--run", type=Path, default=shipped_model())
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results")
    parser.add_argument("--max-objects", type=int, default=2)
    parser.add_argument("--target-views", type=int, default=5)
    parser.add_argument("--scale", type=float, default=0.25)
    parser.add_argument("--mesh-resolution", type=int, default=96)
    parser.add_argument("--device", default="cpu", help="cpu or cuda")
    args = parser.parse_args()
    ds = Dataset.open(args.data)
    objects = [ds.load_object(e) for e in interleave_categories(ds.objects("val"), args.max_objects)]
    protocol = ProtocolConfig(1, args.target_views, args.scale, 0, metrics_3d=True)
    loaded = load_model(args.run, torch.device(args.device))
    rows = []
    for name, settings in VARIANTS:
        mean, seconds = run_variant(
            loaded, settings, objects, protocol, len(ds.affordance_classes), args.mesh_resolution
        )
        rows.append({"name": name, "settings": settings, "mean": {k: mean[k] for k in KEYS},
                     "seconds_per_object": seconds / len(objects)})  # fmt: skip
        print(f"{name}: " + ", ".join(f"{k} {mean[k]:.3f}" for k in KEYS), flush=True)
    header = (f"Validation split, first {args.max_objects} objects per category ({len(objects)} objects), 1 input "
              f"view, {args.target_views} target views at {args.scale:g} of the dataset's resolution, meshes at "
              f"{args.mesh_resolution}³; model {args.run}. Seconds per object: rendering and meshing too.")  # fmt: skip
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "inversion_sweep.md").write_text(markdown(rows, header))
    write_json_atomic(args.out / "inversion_sweep.json", {
        "benchmark": "inversion_sweep", "default": asdict(DEFAULT), "rows": rows,
        "settings": {k: str(v) for k, v in vars(args).items()},
        "machine": {"platform": platform.platform(), "cpu_count": os.cpu_count(),
                    "torch_threads": torch.get_num_threads(), "torch": torch.__version__,
                    "gpu": torch.cuda.get_device_name(0) if args.device == "cuda" else None,
                    "date": time.strftime("%Y-%m-%d %H:%M:%S")},
    })  # fmt: skip


if __name__ == "__main__":
    main()
