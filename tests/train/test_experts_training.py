"""Training with weight experts: the router learns the families, the experts part, a run resumes exactly, and a
wrong number of experts is refused in one line."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import torch
from support import straight_and_resumed_weights

from affnerf.errors import AffnerfError
from affnerf.train.trainer import train


def _with_experts(config, experts: int):
    return replace(config, model=replace(config.model, experts=experts), points_weight=0.1)


def test_the_router_learns_the_families_and_the_experts_part(tiny_train_config):
    config = _with_experts(tiny_train_config(steps=40, checkpoint_every=40), experts=2)
    config = replace(config, model=replace(config.model, router_weight=1.0), optim=replace(config.optim, lr=3e-3))
    train(config)
    rows = [json.loads(line) for line in (config.out / "metrics.jsonl").read_text().splitlines()]
    router = [r["loss/router"] for r in rows]
    assert np.mean(router[-5:]) < 0.5 * np.mean(router[:5]), router
    weights = torch.load(config.out / "checkpoints" / "step_00000040.pt", weights_only=True)["model"]
    trunk = [v for k, v in weights.items() if "trunk_layers" in k and k.endswith("weight")]
    assert trunk and all(w.shape[0] == 2 for w in trunk)
    assert all((w[0] - w[1]).abs().max() > 1e-4 for w in trunk)  # each family's objects moved their own set


def test_an_expert_run_resumes_to_the_same_weights(tiny_train_config, tmp_path):
    straight = _with_experts(tiny_train_config(out=tmp_path / "straight"), experts=2)
    a, b = straight_and_resumed_weights(straight, stop_at=10)
    assert any(k.startswith("router.") for k in a)
    assert all(torch.equal(a[k], b[k]) for k in a)


def test_experts_must_match_the_training_families(tiny_train_config):
    config = _with_experts(tiny_train_config(), experts=3)
    with pytest.raises(AffnerfError, match=r"dataset\.json: --model\.experts 3 .* has 2 \(bottle, screwdriver\)"):
        train(config)


def test_an_expert_model_started_from_a_plain_run_computes_what_the_run_did(tiny_train_config, train_dataset):
    from affnerf.data.dataset import Dataset
    from affnerf.model.registry import build_model
    from affnerf.train.state import initial_weights

    config = tiny_train_config(steps=10, checkpoint_every=10)
    train(config)
    classes = len(Dataset.open(train_dataset).affordance_classes)
    plain = build_model(config.model, classes)
    experts = build_model(replace(config.model, experts=2), classes)
    initial_weights(config.out, plain, classes)
    initial_weights(config.out, experts, classes)
    images = torch.rand(2, 1, 3, 32, 32)
    cams = torch.zeros(2, 1, 4), torch.eye(4).expand(2, 1, 4, 4)
    points, obj = torch.rand(50, 3) * 0.3 - 0.15, torch.arange(2).repeat_interleave(25)
    a = plain.point_geometry(plain.encode_views(images, *cams), obj, points)[-1]
    b = experts.point_geometry(experts.encode_views(images, *cams), obj, points)[-1]
    torch.testing.assert_close(a.logits, b.logits)
    torch.testing.assert_close(a.density, b.density)
