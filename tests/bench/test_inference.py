"""The inference benchmark measures both paths and compares their outputs (tiny sizes, so only shape and sense)."""

from __future__ import annotations

import numpy as np

from affnerf.bench.inference import measure_inference
from affnerf.predict.loading import load_model


def test_measure_inference_reports_fast_and_reference(trained_runs):
    loaded = load_model(trained_runs["affnerf"])
    size = loaded.model.config.encoder_resolution
    crop = np.full((size, size, 3), 255, np.uint8)
    crop[size // 4 : 3 * size // 4, size // 3 : 2 * size // 3] = (90, 60, 30)
    out = measure_inference(loaded, crop, repeats=1, views=2, size=(24, 18), resolution=16)
    assert out["chunk"] == 1024 and out["views"] == 2
    for key in ("image_to_view", "image_to_mesh"):
        assert out[key]["fast"]["median"] > 0 and out[key]["reference"]["median"] > 0
        assert out[key]["speedup"] == out[key]["reference"]["median"] / out[key]["fast"]["median"]
    assert 0.0 <= out["image_to_view"]["label_agreement"] <= 1.0
    assert set(out["image_to_mesh"]["faces"]) == {"fast", "reference"}
