"""``--optim.weight-decay``: AdamW on the encoders' weights only, refused when negative, resumed exactly."""

from __future__ import annotations

from dataclasses import replace

import torch
from support import train_argv

from affnerf.cli.main import main
from affnerf.model.registry import build_model
from affnerf.train.state import decay_groups, make_optimizer
from affnerf.train.trainer import train


def _small_model(tiny_train_config) -> torch.nn.Module:
    return build_model(tiny_train_config().model, 4)


def test_only_the_encoders_matrices_and_kernels_decay(tiny_train_config):
    model = _small_model(tiny_train_config)
    decayed, rest = decay_groups(model, 0.1)
    names = {id(p): n for n, p in model.named_parameters()}
    assert decayed["weight_decay"] == 0.1 and rest["weight_decay"] == 0.0
    assert decayed["params"] and all("encoder" in names[id(p)] and p.ndim >= 2 for p in decayed["params"])
    kept = [names[id(p)] for p in rest["params"]]
    assert any(n.startswith("renderer") and n.endswith("weight") for n in kept)  # the field's matrices stay
    assert any("encoder" in n and "norm" in n for n in kept)  # so do the encoders' GroupNorm scales
    assert len(decayed["params"]) + len(rest["params"]) == len(list(model.parameters()))


def test_a_step_with_no_gradient_shrinks_encoder_weights_by_lr_times_decay_and_nothing_else(tiny_train_config):
    model = _small_model(tiny_train_config)
    before = {n: p.detach().clone() for n, p in model.named_parameters()}
    optimizer = make_optimizer(model, 0.01, torch.device("cpu"), weight_decay=0.5)
    for p in model.parameters():
        p.grad = torch.zeros_like(p)
    optimizer.step()
    for name, p in model.named_parameters():
        shrunk = "encoder" in name and p.ndim >= 2
        expected = before[name] * (1 - 0.01 * 0.5) if shrunk else before[name]
        torch.testing.assert_close(p.detach(), expected, rtol=1e-6, atol=1e-7)
    plain = make_optimizer(model, 0.01, torch.device("cpu"))  # no decay: Adam itself (AdamW subclasses it), one group
    assert type(plain) is torch.optim.Adam and len(plain.param_groups) == 1


def test_a_negative_decay_is_one_clear_line(tiny_train_config, capsys):
    config = tiny_train_config()
    assert main(train_argv(config, "--optim.weight-decay", "-0.1")) == 2
    assert "--optim.weight-decay is 0 (none) or positive, not -0.1" in capsys.readouterr().err
    assert not (config.out / "checkpoints").exists()


def test_a_model_without_image_encoders_refuses_the_decay_in_one_line(tiny_train_config, capsys):
    config = tiny_train_config()
    argv = train_argv(config, "--optim.weight-decay", "0.1", "--model.kind", "pixelnerf", "--input-views", "3")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--optim.weight-decay decays the image encoders of affnerf, pose-aware models; a pixelnerf model" in err
    assert not (config.out / "checkpoints").exists()


def test_a_decaying_run_resumes_to_the_same_weights(tiny_train_config, tmp_path):
    config = tiny_train_config(optim=replace(tiny_train_config().optim, weight_decay=0.2))
    train(config)
    whole = torch.load(config.out / "checkpoints" / "step_00000020.pt", weights_only=True)
    assert [g["weight_decay"] for g in whole["optimizer"]["param_groups"]] == [0.2, 0.0]
    halves = replace(config, out=tmp_path / "halves", stop_at=10)
    train(halves)
    train(replace(halves, stop_at=0, resume=True))
    resumed = torch.load(halves.out / "checkpoints" / "step_00000020.pt", weights_only=True)
    assert all(torch.equal(resumed["model"][k], whole["model"][k]) for k in whole["model"])
    plain = tiny_train_config(out=tmp_path / "plain")
    train(plain)
    other = torch.load(plain.out / "checkpoints" / "step_00000020.pt", weights_only=True)
    assert any(not torch.equal(other["model"][k], whole["model"][k]) for k in whole["model"] if "encoder" in k)
