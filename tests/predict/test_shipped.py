"""The shipped model and the export that makes one: same predictions, no training state."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.data.cameras import Intrinsics
from affnerf.model.views import render_view
from affnerf.predict.predictor import Predictor, turntable_poses
from affnerf.predict.shipped import export_for_inference, shipped_model


def test_exported_checkpoint_predicts_the_same_and_is_smaller(trained_runs, tmp_path):
    run = trained_runs["affnerf"]
    slim = export_for_inference(run, tmp_path / "slim.pt")
    data = torch.load(slim, map_location="cpu", weights_only=True)
    assert "optimizer" not in data and "rank_states" not in data
    full = max((run / "checkpoints").glob("*.pt"))
    assert slim.stat().st_size < full.stat().st_size
    crops = np.random.default_rng(0).integers(0, 255, (1, 64, 64, 3), dtype=np.uint8)
    intr, pose = Intrinsics.from_fov(16, 12, 1.0), turntable_poses(4)[1]
    renders = []
    for path in (run, slim):
        predictor = Predictor.load(path, "cpu", fast=False)
        size = predictor.loaded.model.config.encoder_resolution
        codes = predictor.encode_crops(crops[:, :size, :size])
        renders.append(render_view(predictor.loaded.model, codes, intr, pose))
    assert np.array_equal(renders[0].rgb, renders[1].rgb)
    assert np.array_equal(renders[0].affordance, renders[1].affordance)


def test_shipped_model_loads_and_is_small():
    path = shipped_model()
    assert path.stat().st_size <= 25 * 2**20
    predictor = Predictor.load(path, "cpu")
    assert predictor.classes[0] == "background" and "grasp" in predictor.classes
    assert predictor.loaded.model.config.kind == "affnerf"
