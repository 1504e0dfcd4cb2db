"""AFF-NeRF's input-view labelling head: the shape encoder labels its crop's pixels while training."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
import torch
from support import TINY_MODEL

from affnerf.errors import AffnerfError
from affnerf.model.affnerf import AffNeRF, Codes, LabelledCodes, view_label_loss
from affnerf.model.registry import build_model
from affnerf.model.resnet import CodeEncoder


def test_the_labelling_head_leaves_the_code_as_it_is_and_labels_quarter_resolution_pixels():
    torch.manual_seed(0)
    plain = CodeEncoder(16, 0.25).eval()
    labelled = CodeEncoder(16, 0.25, label_classes=5).eval()
    labelled.load_state_dict(plain.state_dict(), strict=False)
    images = torch.rand(3, 3, 64, 64)
    code, logits = labelled.encode(images)
    torch.testing.assert_close(code, plain(images))
    assert logits.shape == (3, 5, 16, 16)
    assert labelled.encode(images, labels=False)[1] is None and plain.encode(images)[1] is None


def test_the_view_label_loss_is_near_zero_for_right_logits_and_log_c_for_flat_ones():
    labels = torch.randint(0, 4, (2, 1, 8, 8))
    right = 50.0 * torch.nn.functional.one_hot(labels, 4).permute(0, 1, 4, 2, 3).float()
    assert view_label_loss(right, labels) < 1e-3
    assert view_label_loss(torch.zeros(2, 1, 4, 2, 2), labels) == pytest.approx(math.log(4), rel=1e-5)


def test_affnerf_adds_the_loss_only_while_training_with_the_head():
    config = replace(TINY_MODEL, view_affordance_weight=0.5)
    model = AffNeRF(config, num_classes=4)
    images, labels = torch.rand(2, 1, 3, 32, 32), torch.randint(0, 4, (2, 1, 32, 32))
    none = torch.zeros(2, 1, 4), torch.eye(4).expand(2, 1, 4, 4)
    codes = model.train().encode_views(images, *none)
    assert isinstance(codes, LabelledCodes) and codes.view_logits.shape == (2, 1, 4, 8, 8)
    loss = model.auxiliary_losses(codes, None, labels)["loss/view_affordance"]
    torch.testing.assert_close(loss, 0.5 * view_label_loss(codes.view_logits, labels))
    loss.backward()
    assert model.shape_encoder.backbone.stem[0].weight.grad.abs().sum() > 0  # it trains the shape encoder
    assert model.appearance_encoder.backbone.stem[0].weight.grad is None
    evaluated = model.eval().encode_views(images, *none)
    assert type(evaluated) is Codes and model.auxiliary_losses(evaluated, None, labels) == {}
    paper = AffNeRF(TINY_MODEL, num_classes=4).train()
    assert paper.shape_encoder.label_head is None
    assert paper.auxiliary_losses(paper.encode_views(images, *none), None, labels) == {}


def test_the_loss_teaches_the_encoder_to_find_a_small_part():
    # a grey square on white with a small red patch at a random corner: the patch is class 2, the rest class 1
    torch.manual_seed(0)
    enc = CodeEncoder(8, 0.25, label_classes=3)
    opt = torch.optim.Adam(enc.parameters(), lr=3e-3)

    def batch(n: int = 8) -> tuple[torch.Tensor, torch.Tensor]:
        images, labels = torch.ones(n, 3, 32, 32), torch.zeros(n, 1, 32, 32, dtype=torch.long)
        for i in range(n):
            images[i, :, 8:24, 8:24], labels[i, 0, 8:24, 8:24] = 0.5, 1
            y, x = 8 + 8 * int(torch.randint(0, 2, ())), 8 + 8 * int(torch.randint(0, 2, ()))
            images[i, :, y : y + 8, x : x + 8] = torch.tensor([0.9, 0.1, 0.1])[:, None, None]
            labels[i, 0, y : y + 8, x : x + 8] = 2
        return images, labels

    for _ in range(60):
        images, labels = batch()
        loss = view_label_loss(enc.encode(images)[1][:, None], labels)
        opt.zero_grad()
        loss.backward()
        opt.step()
    images, labels = batch(16)
    logits = torch.nn.functional.interpolate(enc.eval().encode(images)[1], size=(32, 32), mode="bilinear")
    found = logits.argmax(1)[labels[:, 0] == 2]
    assert (found == 2).float().mean() > 0.8


def test_only_affnerf_takes_the_head():
    with pytest.raises(AffnerfError, match="view-affordance-weight"):
        build_model(replace(TINY_MODEL, kind="pixelnerf", view_affordance_weight=0.1), 4)
