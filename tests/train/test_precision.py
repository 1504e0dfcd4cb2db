"""--precision: the forward pass in bfloat16 under autocast, the weights and optimiser state in float32."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from affnerf.train.checkpoint import list_checkpoints, load_checkpoint
from affnerf.train.config import PAPER, SMALL
from affnerf.train.precision import PRECISIONS, forward_precision
from affnerf.train.trainer import train


def test_both_presets_train_in_float32_and_the_choices_are_fp32_and_bf16():
    assert PAPER.precision == SMALL.precision == "fp32"
    assert PRECISIONS == ("fp32", "bf16")


@pytest.mark.parametrize(("precision", "dtype"), [("fp32", torch.float32), ("bf16", torch.bfloat16)])
def test_a_layer_runs_in_the_chosen_precision_and_its_gradient_stays_float32(precision, dtype):
    layer = torch.nn.Linear(8, 4)
    with forward_precision(precision, torch.device("cpu")):
        out = layer(torch.randn(16, 8))
    assert out.dtype == dtype
    out.float().square().mean().backward()
    assert layer.weight.grad is not None and layer.weight.grad.dtype == torch.float32


def test_a_bf16_run_learns_like_an_fp32_one_and_keeps_float32_weights(tiny_train_config):
    losses = {}
    for precision in PRECISIONS:
        config = tiny_train_config(steps=30, precision=precision, out=tiny_train_config().out.with_name(precision))
        train(config)
        rows = [json.loads(line) for line in (config.out / "metrics.jsonl").read_text().splitlines()]
        losses[precision] = np.array([r["loss/total"] for r in rows])
        state = load_checkpoint(list_checkpoints(config.out / "checkpoints")[-1])
        assert all(t.dtype == torch.float32 for t in state["model"].values() if t.is_floating_point())
        assert json.loads((config.out / "config.json").read_text())["precision"] == precision
    assert np.isfinite(losses["bf16"]).all()
    assert not np.array_equal(losses["bf16"], losses["fp32"])  # the trainer did run the forward pass in bfloat16
    assert losses["bf16"][-5:].mean() < 0.8 * losses["bf16"][:5].mean()  # it learns
    assert np.abs(losses["bf16"] - losses["fp32"]).max() < 0.1 * losses["fp32"].max()  # as fp32 does, step by step
