"""Inference-time variants of the shipped model that cost no training (issue 12), each scored by `affnerf eval` on
40 validation objects (5 per category, input view 0, 5 target views at 100×75, meshes at 96³; the `val40`
protocol of benchmarks/side_by_side.sh). One variant per process: each patches the library in this process only.

- ``base``: the shipped model as `affnerf eval` runs it (fast path: 32 samples a ray in the occupancy grid).
- ``full-sampling``: coarse-to-fine sampling as in training (``--no-fast``; 24 + 24 samples a ray), 2D only.
- ``full-sampling-48``: the same with 48 coarse + 48 fine samples (the checkpoint's ``num_coarse``/``num_fine``,
  which are not architecture, raised), 2D only.
- ``crops-A,B,C``: the codes averaged over encoder crops of the input view with margins A, B, C (the shipped crop
  has margin 0.08, :data:`affnerf.data.crop.CROP_MARGIN`), as AFF-NeRF averages several views' codes.
- ``mirror-T``: per object, the density on a 48³ grid is compared with its mirror image across x = 0 and y = 0
  (IoU of the cells above half the surface density); when the better IoU reaches T, density, affordance logits
  and colour are averaged over each point and its mirror image (the canonical frames put each family's plane of
  symmetry through the origin, conventions §1).
- ``smooth-S``: the density grid of the labelled mesh blurred by a Gaussian of S millimetres before the level and
  marching cubes (3D only; the ripples of about a centimetre the meshes show, `results/pe_frequencies.md`).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/inference_variants.py --data DATA --variant VARIANT \\
        --out W/VARIANT
    .venv/bin/python benchmarks/inference_variants.py --report W/base W/... --markdown OUT.md --json OUT.json
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
import torch

from affnerf.cli.main import main as affnerf_main
from affnerf.data.crop import crop_intrinsics, crop_object, crop_window
from affnerf.environment import describe_machine
from affnerf.eval.methods import affnerf as method_module
from affnerf.fileio import write_json_atomic
from affnerf.model.field import ConditionalField, FieldOutput
from affnerf.predict import mesh as mesh_module
from affnerf.predict.mesh import evaluate_grid, grid_spacing
from affnerf.predict.shipped import shipped_model

KEYS = ("mIoU", "PA", "MPA", "mIoU_object", "PSNR", "fscore_1cm", "affordance_miou_3d")
MIRROR_GRID = 48


def multi_margin_views(margins: list[float]):
    """A stand-in for :func:`affnerf.model.inputs.dataset_views` that gives every view once per crop margin."""

    def dataset_views(obj, views, size):
        k = obj.record.intrinsics
        crops, intr, poses = [], [], []
        for view in views:
            rgb, mask = obj.rgb(view), obj.affordance(view) > 0
            for margin in margins:
                crops.append(crop_object(rgb, mask, size, obj.record.background_color, margin))
                intr.append(crop_intrinsics(k.fl_x, k.fl_y, k.cx, k.cy, crop_window(mask, margin), size))
                poses.append(obj.pose(view))
        images = torch.from_numpy(np.stack(crops)).permute(0, 3, 1, 2).float()[None] / 255.0
        return images, torch.tensor([intr], dtype=torch.float32), torch.from_numpy(np.stack(poses)).float()[None]

    return dataset_views


def mirror_ious(occupied: np.ndarray) -> list[float]:
    """IoU of an (R, R, R) occupancy grid, indexed [x, y, z] symmetrically about 0, with its mirror across x = 0
    and across y = 0."""
    out = []
    for axis in (0, 1):
        flipped = np.flip(occupied, axis=axis)
        out.append(float((occupied & flipped).sum() / max((occupied | flipped).sum(), 1)))
    return out


def patch_mirror(threshold: float, log: list[dict]) -> None:
    """Make every field evaluation the mean over the point and its mirror image, for the objects whose density is
    at least ``threshold`` symmetric (see the module docstring)."""
    state: dict = {"axis": None}
    forward, density_only, geometry = ConditionalField.forward, ConditionalField.density_only, ConditionalField.geometry

    def mirrored(p: torch.Tensor) -> torch.Tensor:
        q = p.clone()
        q[..., state["axis"]] = -q[..., state["axis"]]
        return q

    def sym_forward(self, points, dirs, shape_code, appearance_code):
        a = forward(self, points, dirs, shape_code, appearance_code)
        if state["axis"] is None:
            return a
        b = forward(self, mirrored(points), mirrored(dirs), shape_code, appearance_code)
        return FieldOutput((a.sigma + b.sigma) / 2, (a.rgb + b.rgb) / 2, (a.logits + b.logits) / 2)

    def sym_density(self, points, shape_code):
        a = density_only(self, points, shape_code)
        return a if state["axis"] is None else (a + density_only(self, mirrored(points), shape_code)) / 2

    def sym_geometry(self, points, shape_code):
        s, logits = geometry(self, points, shape_code)
        if state["axis"] is None:
            return s, logits
        s2, logits2 = geometry(self, mirrored(points), shape_code)
        return (s + s2) / 2, (logits + logits2) / 2

    ConditionalField.forward, ConditionalField.density_only = sym_forward, sym_density
    ConditionalField.geometry = sym_geometry
    encoded = method_module.ConditionedNeRFMethod.encoded

    def choose_plane(self, obj, inputs):
        fresh = self._key != (obj.record.object_id, tuple(inputs))
        if fresh:
            state["axis"] = None
        encoding = encoded(self, obj, inputs)
        if fresh:
            model = self.loaded.model
            with torch.no_grad():
                volume = evaluate_grid(model.point_fields(encoding)[0], MIRROR_GRID, model.config.scene_half_extent)
            ious = mirror_ious(volume > model.config.surface_density / 2)
            best = int(np.argmax(ious))
            state["axis"] = best if ious[best] >= threshold else None
            log.append({"object": obj.record.object_id, "iou_x": ious[0], "iou_y": ious[1], "axis": state["axis"]})
        return encoding

    method_module.ConditionedNeRFMethod.encoded = choose_plane


def patch_smoothing(sigma_m: float) -> None:
    """Blur every density grid that mesh extraction evaluates by a Gaussian of ``sigma_m`` metres."""
    from scipy.ndimage import gaussian_filter

    def smoothed(fn, resolution, half_extent, *args, **kwargs):
        volume = evaluate_grid(fn, resolution, half_extent, *args, **kwargs)
        sigma = sigma_m / grid_spacing(resolution, half_extent)
        return gaussian_filter(volume, sigma, mode="constant").astype(np.float32)

    mesh_module.evaluate_grid = smoothed


def samples_checkpoint(run: Path, coarse: int, fine: int, folder: Path) -> Path:
    """A copy of the checkpoint with other samples per ray (not architecture: the weights are the same)."""
    data = torch.load(run, map_location="cpu", weights_only=False)
    data["model_config"] = {**data["model_config"], "num_coarse": coarse, "num_fine": fine}
    path = folder / f"samples_{coarse}_{fine}.pt"
    torch.save(data, path)
    return path


def run_variant(variant: str, data: Path, run: Path, out: Path) -> dict:
    """Patch for ``variant``, run the val40 evaluation into ``out``, and return its mean metrics."""
    extra, log = [], []
    tmp = tempfile.TemporaryDirectory()
    if variant.startswith("full-sampling"):
        extra = ["--no-fast", "--no-metrics-3d"]
        if variant == "full-sampling-48":
            run = samples_checkpoint(run, 48, 48, Path(tmp.name))
    elif variant.startswith("crops-"):
        method_module.dataset_views = multi_margin_views([float(m) for m in variant[6:].split(",")])
    elif variant.startswith("mirror-"):
        patch_mirror(float(variant[7:]), log)
    elif variant.startswith("smooth-"):
        patch_smoothing(float(variant[7:]) / 1000.0)
    elif variant != "base":
        raise SystemExit(f"unknown variant {variant!r}")
    args = ["eval", "--run", str(run), "--data", str(data), "--split", "val", "--method", "affnerf", "--scale",
            "0.25", "--target-views", "5", "--max-objects", "5", "--mesh-resolution", "96", "--device", "cpu",
            "--out", str(out), *extra]  # fmt: skip
    code = affnerf_main(args)
    if code:
        raise SystemExit(code)
    tmp.cleanup()
    mean = json.loads((out / "metrics_affnerf.json").read_text())["mean"]
    result = {"variant": variant, "mean": {k: mean[k] for k in KEYS if k in mean}, "mirror_planes": log}
    write_json_atomic(out / "variant.json", result)
    return result


def report(folders: list[Path], markdown: Path, json_out: Path) -> None:
    """One table of every variant's ``variant.json``, and the JSON of them all with the machine."""
    results = [json.loads((f / "variant.json").read_text()) for f in folders]
    rows = ["| variant | " + " | ".join(KEYS) + " |", "| --- |" + " --- |" * len(KEYS)]
    for r in results:
        cells = [f"{r['mean'][k]:.4f}" if k in r["mean"] else "–" for k in KEYS]
        rows.append(f"| {r['variant']} | " + " | ".join(cells) + " |")
    markdown.write_text("\n".join(rows) + "\n")
    write_json_atomic(json_out, {"benchmark": "inference_variants", "machine": describe_machine(), "runs": results})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path)
    parser.add_argument("--run", type=Path, default=None, help="default: the shipped model")
    parser.add_argument("--variant", default="base")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--report", type=Path, nargs="*", default=None, help="variant folders to tabulate")
    parser.add_argument("--markdown", type=Path)
    parser.add_argument("--json", type=Path)
    a = parser.parse_args()
    if a.report:
        report(a.report, a.markdown, a.json)
        return
    print(json.dumps(run_variant(a.variant, a.data, a.run or shipped_model(), a.out)["mean"]))


if __name__ == "__main__":
    main()
