"""Test-time variants that were tried and not kept (issue 12), measured on validation objects.

1. **Code-bank initialisation of the fit** (``--part bank``): the codes of the nearest training objects (each the
   mean of its encoded codes over 4 views, as retrieval's bank) compete with the encoder's codes as the fit's
   starting point. Each candidate gets the camera search of :func:`affnerf.predict.invert.search_cameras`; the one
   with the lowest photometric loss at its best camera is fitted (:func:`fit_codes`). Scored like
   ``inversion_sweep.py``: first 2 validation objects per category, 1 input view, 5 target views at 0.25, meshes
   at 96³.
2. **Label decision rules at novel views** (``--part rules``), encoder's codes: the protocol's argmax over
   (background, classes); object where opacity exceeds τ, then the most likely object class; the model's own
   labelled mesh (marching cubes at the stored level) ray-cast at the target cameras; the mesh's silhouette with
   the volume's object labels. First 5 validation objects per category, 5 target views at 0.5.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/test_time_variants.py --data DATA --part bank|rules \\
        --out benchmarks/results/test_time_variants_PART.json
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch

from affnerf.data.dataset import Dataset, ObjectData, interleave_categories
from affnerf.data.raycast import FrameCaster
from affnerf.data.writer import surface_from_record
from affnerf.environment import describe_machine
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod
from affnerf.eval.methods.affnerf_fit import FittedAffNeRFMethod
from affnerf.eval.methods.retrieval import RetrievalMethod
from affnerf.eval.protocol import ProtocolConfig, choose_views, evaluate, object_targets
from affnerf.fileio import write_json_atomic
from affnerf.metrics.segmentation import confusion_matrix, segmentation_metrics
from affnerf.model.affnerf import Codes
from affnerf.model.views import RenderedView, render_view
from affnerf.predict.invert import (
    InversionConfig,
    crop_loss,
    dataset_crop_target,
    fit_codes,
    object_points,
    render_crop,
    search_cameras,
    target_tensors,
)
from affnerf.predict.loading import LoadedModel, load_model
from affnerf.predict.shipped import shipped_model

KEYS = ("mIoU", "PA", "MPA", "mIoU_object", "PSNR", "fscore_1cm", "affordance_miou_3d")


class BankStartMethod(FittedAffNeRFMethod):
    """``affnerf-fit`` whose start is the best of the encoder's codes and the ``nearest`` closest bank codes.

    Args:
        bank: (shape (N, D), appearance (N, D)) codes of the training objects.
        nearest: bank candidates by shape-code distance.
        fit: fit the chosen candidate (False: render it as it is).
    """

    def __init__(self, *args, bank: tuple[np.ndarray, np.ndarray], nearest: int, fit: bool = True, **kwargs):
        super().__init__(*args, **kwargs)
        self.bank, self.nearest, self.fit = bank, nearest, fit
        self.name, self.picks = "affnerf-fit-bank", []

    def candidates(self, codes: Codes) -> list[Codes]:
        """The encoder's codes, then the nearest bank entries' codes."""
        shapes, looks = self.bank
        order = np.argsort(((shapes - codes.shape[0].numpy()) ** 2).sum(1))[: self.nearest]
        return [codes] + [
            Codes(torch.from_numpy(shapes[i][None]).float(), torch.from_numpy(looks[i][None]).float()) for i in order
        ]

    def start(self, codes: Codes, target, config: InversionConfig) -> tuple[float, np.ndarray, np.ndarray]:
        """Photometric loss at the best searched camera, that camera (3,) and the occupied cells (P, 3)."""
        model, bg = self.loaded.model, np.asarray(self.loaded.background)
        points = object_points(model, codes, config.search_resolution, model.config.occupancy_density)
        camera = search_cameras(model, codes, points, target, bg, config)[0][0]
        pixels, rgb, mask, k = target_tensors(target, config.resolution, torch.device("cpu"))
        with torch.no_grad():
            stages = render_crop(model, codes, torch.from_numpy(camera), pixels, k, torch.as_tensor(bg).float())
            return float(crop_loss(stages, rgb, mask, config.mask_weight)), camera, points

    def encode(self, obj: ObjectData, inputs: list[int]) -> Codes:
        model = self.loaded.model
        for p in model.parameters():
            p.requires_grad_(False)
        target = dataset_crop_target(obj, inputs[0], model.config.encoder_resolution)
        config = replace(self.inversion, seed=self.inversion.seed + inputs[0])
        options = self.candidates(ConditionedNeRFMethod.encode(self, obj, inputs[:1]))
        starts = [self.start(c, target, config) for c in options]
        best = int(np.argmin([s[0] for s in starts]))
        self.picks.append(best)
        if not self.fit:
            return options[best]
        _, camera, points = starts[best]
        anchors = points[np.random.default_rng(config.seed).permutation(len(points))[: config.anchor_points]]
        bg = np.asarray(self.loaded.background)
        return fit_codes(model, options[best], target, camera, bg, config, anchors)[0]


@torch.no_grad()
def code_bank(loaded: LoadedModel, ds: Dataset, views: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """(N, D) shape and (N, D) appearance codes of the train split, each the mean over ``views`` views."""
    method = ConditionedNeRFMethod(loaded)
    shapes, looks = [], []
    for entry in ds.objects(split="train"):
        obj = ds.load_object(entry)
        codes = method.encode(obj, np.linspace(0, len(obj) - 1, views).round().astype(int).tolist())
        shapes.append(codes.shape[0].numpy())
        looks.append(codes.appearance[0].numpy())
    return np.stack(shapes), np.stack(looks)


def bank_part(loaded: LoadedModel, ds: Dataset) -> list[dict]:
    """Rows of the code-bank comparison."""
    objects = [ds.load_object(e) for e in interleave_categories(ds.objects("val"), 2)]
    protocol = ProtocolConfig(1, 5, 0.25, 0, metrics_3d=True)
    bank = code_bank(loaded, ds)
    methods = [
        ("fit from the encoder's codes (default)", FittedAffNeRFMethod(loaded, mesh_resolution=96)),
        ("fit from the best of encoder + 3 nearest bank codes", BankStartMethod(loaded, mesh_resolution=96,
                                                                                bank=bank, nearest=3)),
        ("best of encoder + 3 nearest bank codes, no fit", BankStartMethod(loaded, mesh_resolution=96, bank=bank,
                                                                           nearest=3, fit=False)),
        ("retrieval", RetrievalMethod(loaded, ds)),
    ]  # fmt: skip
    rows = []
    for name, method in methods:
        mean = evaluate(method, objects, protocol, "val", len(ds.affordance_classes), 0).to_json()["mean"]
        rows.append({"variant": name, "mean": {k: mean[k] for k in KEYS}, "picks": getattr(method, "picks", None)})
        print(name, {k: round(mean[k], 3) for k in KEYS}, flush=True)
    return rows


def rule_labels(views: list[RenderedView], cast: list[np.ndarray]) -> dict[str, np.ndarray]:
    """(K, H, W) labels of each decision rule from the rendered views and the mesh's cast labels."""
    inside = np.stack([v.affordance[..., 1:].argmax(-1) + 1 for v in views])
    opacity = np.stack([v.opacity for v in views])
    rules = {"argmax (protocol)": np.stack([v.labels for v in views])}
    for tau in (0.3, 0.4, 0.5, 0.6, 0.7):
        rules[f"opacity > {tau}, then argmax of object classes"] = np.where(opacity > tau, inside, 0)
    rules["the labelled mesh, ray-cast"] = np.stack(cast)
    rules["the mesh's silhouette, the volume's object labels"] = np.where(np.stack(cast) > 0, inside, 0)
    return {k: v.astype(np.uint8) for k, v in rules.items()}


def rules_part(loaded: LoadedModel, ds: Dataset) -> list[dict]:
    """Rows of the decision-rule comparison (2D metrics, mean over categories)."""
    method, classes = ConditionedNeRFMethod(loaded, mesh_resolution=128), len(ds.affordance_classes)
    protocol, confusions = ProtocolConfig(1, 5, 0.5, 0), {}
    for obj in (ds.load_object(e) for e in interleave_categories(ds.objects("val"), 5)):
        inputs, targets = choose_views(len(obj), obj.record.object_id, protocol)
        ts, gt, _ = object_targets(obj, targets, protocol.scale)
        codes, grid = method.encoded(obj, inputs), method.occupancy(obj, inputs)
        views = [render_view(loaded.model, codes, ts.intrinsics, p, ts.background, 4096, grid) for p in ts.poses]
        mesh = method.mesh(obj, inputs)
        caster = FrameCaster(surface_from_record(mesh), ts.background) if len(mesh.faces) else None
        cast = [caster.cast_frame(ts.intrinsics, p).affordance if caster else v.labels * 0 for p, v in
                zip(ts.poses, views, strict=True)]  # fmt: skip
        for rule, labels in rule_labels(views, cast).items():
            per_cat = confusions.setdefault(rule, {})
            per_cat[obj.record.category] = per_cat.get(obj.record.category, 0) + confusion_matrix(gt, labels, classes)
    rows = []
    for rule, per_cat in confusions.items():
        scores = {c: segmentation_metrics(m) for c, m in per_cat.items()}
        mean = {k: float(np.mean([s[k] for s in scores.values()])) for k in ("mIoU", "PA", "MPA", "mIoU_object")}
        rows.append({"variant": rule, "mean": mean, "mIoU_per_category": {c: s["mIoU"] for c, s in scores.items()}})
        print(rule, {k: round(v, 4) for k, v in mean.items()}, flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--part", choices=("bank", "rules"), required=True)
    parser.add_argument("--run", type=Path, default=shipped_model())
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    ds, loaded = Dataset.open(args.data), load_model(args.run, torch.device("cpu"))
    rows = bank_part(loaded, ds) if args.part == "bank" else rules_part(loaded, ds)
    write_json_atomic(args.out, {"benchmark": f"test_time_variants/{args.part}", "run": str(args.run),
                                 "rows": rows, "machine": describe_machine()})  # fmt: skip


if __name__ == "__main__":
    main()
