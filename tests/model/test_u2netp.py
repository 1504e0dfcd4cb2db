"""U²-Net-p in PyTorch: its shapes, and the salient model's ONNX weights giving onnxruntime's output."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from support import SEGMENT_EXTRA_MISSING, salient_weights

from affnerf.errors import AffnerfError
from affnerf.model import segmenter as segnet
from affnerf.model.u2netp import RSU, U2NetP, check_weights, execution_order, load_onnx_weights
from affnerf.predict import salient

WEIGHTS = salient_weights("onnx", "onnxruntime")
needs_extra = pytest.mark.skipif(WEIGHTS is None, reason=SEGMENT_EXTRA_MISSING)


@pytest.mark.parametrize("height, pooled", [(7, True), (4, True), (4, False)])
def test_a_residual_u_block_keeps_the_resolution_of_odd_sizes(height, pooled):
    block = RSU(height, 3, 4, 5, pooled=pooled)
    assert block(torch.zeros(2, 3, 37, 23)).shape == (2, 5, 37, 23)


def test_the_network_gives_one_logit_a_pixel_and_six_side_outputs():
    torch.manual_seed(0)
    net = U2NetP().eval()
    with torch.no_grad():
        fused, sides = net.side_logits(torch.rand(1, 3, 50, 70))
    assert fused.shape == (1, 1, 50, 70) and len(sides) == 6
    assert all(s.shape == fused.shape for s in sides)
    assert sum(p.numel() for p in net.parameters()) == 1_125_485  # U²-Net-p's 1.1 M
    assert len(execution_order(net)) == 119


@needs_extra
def test_the_onnx_weights_reproduce_onnxruntime():
    import skimage.data

    net = load_onnx_weights(U2NetP(), check_weights(WEIGHTS), WEIGHTS).eval()
    photo = np.ascontiguousarray(skimage.data.coffee()[::2, ::2])
    x = salient.preprocess(photo)
    session = salient.load_salient_model().session
    expected = session.run(None, {session.get_inputs()[0].name: x})
    with torch.no_grad():
        fused, sides = net.side_logits(torch.from_numpy(x))
    assert np.abs(torch.sigmoid(fused).numpy() - expected[0]).max() < 1e-4
    assert np.abs(torch.sigmoid(sides[5]).numpy() - expected[6]).max() < 1e-4


@needs_extra
def test_an_onnx_file_of_another_network_is_refused_naming_it(tmp_path):
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    weight = numpy_helper.from_array(np.zeros((1, 3, 3, 3), np.float32), "w")
    bias = numpy_helper.from_array(np.zeros(1, np.float32), "b")
    conv = helper.make_node("Conv", ["x", "w", "b"], ["y"], pads=[1, 1, 1, 1])
    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 3, 8, 8])
    y = helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 1, 8, 8])
    graph = helper.make_graph([conv], "tiny", [x], [y], [weight, bias])
    path = tmp_path / "tiny.onnx"
    onnx.save(helper.make_model(graph), str(path))
    with pytest.raises(AffnerfError, match="tiny.onnx: 1 convolutions, U²-Net-p has 119"):
        load_onnx_weights(U2NetP(), path.read_bytes(), path)


def test_a_u2netp_segmenter_pads_to_32_and_survives_save_and_load(tmp_path):
    config = segnet.SegmenterConfig(kind="u2netp", input_side=80)
    x, size = segnet.network_input(np.zeros((30, 50, 3), np.uint8), config)
    assert size == (80, 48) and tuple(x.shape) == (1, 3, 64, 96)
    torch.manual_seed(0)
    model = segnet.build_segmenter(config).eval()
    segnet.save_segmenter(model, tmp_path / "u2.pt")
    loaded = segnet.read_segmenter(tmp_path / "u2.pt")
    photo = np.random.default_rng(0).integers(0, 255, (30, 50, 3), np.uint8)
    assert loaded.config == config
    assert np.array_equal(segnet.object_probability(model, photo), segnet.object_probability(loaded, photo))
