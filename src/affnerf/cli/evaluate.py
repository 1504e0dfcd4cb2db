"""``affnerf eval`` and ``affnerf metrics``: the Table 2 protocol, and scoring label folders of any method."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import tyro
from tyro.extras import SubcommandApp

from affnerf.eval.calibrate import CalibrateConfig
from affnerf.eval.grasps import GraspEvalConfig
from affnerf.eval.runner import EvalConfig

app = SubcommandApp()


@app.command(name="table2", is_default=True)
def table2(config: Annotated[EvalConfig, tyro.conf.arg(name="")]) -> None:
    """Evaluate affordance at novel views like the paper's Table 2 (conventions §5).

    For each object of the split: input views chosen by a fixed seed, K other views as targets; per category one
    confusion matrix over all target views. Writes OUT/metrics_<method>.json (OUT/metrics.json: AFF-NeRF's, or the
    first method's), OUT/table2.md across every method evaluated into OUT, and OUT/figure.png (input | ground truth |
    each method).
    """
    from affnerf.eval.runner import run_eval

    results = run_eval(config)
    for label, m in results.items():
        mean = m["mean"]
        line = f"{label}: mIoU {mean['mIoU']:.3f}  PA {mean['PA']:.3f}  MPA {mean['MPA']:.3f}"
        if mean.get("fscore_1cm") is not None:
            line += f"  F@1cm {mean['fscore_1cm']:.3f}  3D mIoU {mean['affordance_miou_3d']:.3f}"
        print(f"{line}  ({mean['objects']} objects)")
    print(f"-> {config.out / 'table2.md'}")


@app.command(name="grasp")
def grasp(config: Annotated[GraspEvalConfig, tyro.conf.arg(name="")]) -> None:
    """Grasps like the paper's Table 3 (conventions §6).

    For each test object: plan grasps on {its true mesh, the affordance model predicted from one image (fitted to
    that image by --fit-steps of test-time inversion, as affnerf predict does; 0 = the encoder's codes)} ×
    {the whole surface, the task's affordance only (grasp; cabinet: pull)}, and on the true mesh restricted to the
    task part its faces get from the predicted field (the predicted affordance without the predicted shape's
    error); score every grasp on the true mesh at the object's metric size (canonical / scale, or
    --object-size): mean Ferrari-Canny epsilon and its ratio to the whole surface of the same mesh, the share of
    grasps with both contacts on the true task part, the lift success rate in physics and, beside it,
    lift-and-disturb success; and each restricted row minus the whole surface of its mesh, with a 95 % bootstrap
    interval over objects (is the restriction better, or could other objects say otherwise?). Writes
    OUT/table3.md, OUT/grasp_metrics.json and OUT/grasp_objects.json.
    """
    from affnerf.eval.grasp_table import METRICS
    from affnerf.eval.grasps import run_grasp_eval

    summary = run_grasp_eval(config)
    for cond, m in summary["mean"].items():
        parts = [f"{k} {m[k]:.4f}" for k in METRICS if m.get(k) is not None]
        print(f"{cond}: " + ", ".join(parts) + f"; no grasp on {m['no_grasp_objects']}/{m['objects']} objects")
    print(f"-> {config.out / 'table3.md'}")


@app.command(name="calibrate")
def calibrate(config: Annotated[CalibrateConfig, tyro.conf.arg(name="")]) -> None:
    """Choose the density level of a model's meshes (surface_density, surface_optical_depth) on a split.

    For up to --max-objects objects of the split (round-robin over categories), encode the protocol's input view,
    evaluate the density grid once and run marching cubes at each of --levels, ranked by mean F-score at 1 cm
    (ties: higher 3D mIoU, then closest to the current level). Then, at each of the --depth-levels best levels, each
    of --optical-depths (the per-object level that lowers it for diffuse objects; 0 = off) is scored the same way,
    and the best (level, optical depth) pair wins (ties: as before, then the smaller depth). Writes
    RUN/calibration.json and, unless --dry-run, stores both in the run's newest checkpoint (or the --checkpoint
    file).
    """
    from affnerf.eval.calibrate import run_calibration, sweep_lines

    result = run_calibration(config)
    for line in sweep_lines(result):
        print(line)


def metrics(pred: Path, gt: Path, category_map: Path | None = None, out: Path | None = None) -> None:
    """Score a folder of predicted label PNGs against ground-truth label PNGs with the same file names.

    Prints mIoU, PA, MPA and their object-only variants per category (`all` without a category map) and their
    mean, in the conventions §5 schema when written with --out.

    Args:
        pred: folder of predicted label PNGs (8-bit class ids).
        gt: folder of ground-truth label PNGs.
        category_map: JSON or YAML mapping file name (or stem) -> category.
        out: write metrics.json here.
    """
    from affnerf.eval.folders import metrics_text, score_folders
    from affnerf.fileio import write_json_atomic

    result = score_folders(pred, gt, category_map)
    print(metrics_text(result))
    if out is not None:
        write_json_atomic(out, result)
        print(f"-> {out}")
