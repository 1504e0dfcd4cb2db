"""``--optim.encoder-lr-scale``: the image encoders' learning rate a multiple of the schedule's, the field's not."""

from __future__ import annotations

from dataclasses import replace

import torch
from support import train_argv

from affnerf.cli.main import main
from affnerf.model.registry import build_model
from affnerf.train.state import decay_groups, make_optimizer
from affnerf.train.trainer import train


def test_the_encoders_groups_carry_the_scale_and_the_field_does_not(tiny_train_config):
    model = build_model(tiny_train_config().model, 4)
    optimizer = make_optimizer(model, 0.01, torch.device("cpu"), encoder_lr_scale=3.0)
    assert type(optimizer) is torch.optim.Adam
    names = {id(p): n for n, p in model.named_parameters()}
    for group in optimizer.param_groups:
        scaled = group["lr_scale"] == 3.0
        assert all(("encoder" in names[id(p)]) == scaled for p in group["params"])
    assert sum(len(g["params"]) for g in optimizer.param_groups) == len(names)


def test_training_scales_the_encoders_first_step_and_not_the_fields(tiny_train_config, tmp_path):
    def weights_after_one_step(scale: float) -> dict[str, torch.Tensor]:
        config = tiny_train_config(out=tmp_path / f"scale{scale}", steps=1)
        train(replace(config, optim=replace(config.optim, encoder_lr_scale=scale)))
        return torch.load(config.out / "checkpoints" / "step_00000001.pt", weights_only=True)["model"]

    one, two, four = (weights_after_one_step(s) for s in (1.0, 2.0, 4.0))
    for name in one:  # the same start and gradients: an encoder moves by its scale times one step, the field alike
        step = two[name] - one[name]  # (2 - 1) steps of the plain rate
        if "encoder" in name:
            assert step.abs().max() > 0
            torch.testing.assert_close(four[name] - one[name], 3 * step, rtol=1e-3, atol=1e-7)
        else:
            torch.testing.assert_close(two[name], one[name])
            torch.testing.assert_close(four[name], one[name])


def test_a_scale_that_is_not_positive_is_one_clear_line(tiny_train_config, capsys):
    config = tiny_train_config()
    assert main(train_argv(config, "--optim.encoder-lr-scale", "0")) == 2
    assert "--optim.encoder-lr-scale is positive, not 0.0" in capsys.readouterr().err
    assert not (config.out / "checkpoints").exists()


def test_without_a_scale_the_decay_keeps_its_two_groups_so_older_runs_resume():
    model = torch.nn.ModuleDict({"encoder": torch.nn.Linear(2, 2), "field": torch.nn.Linear(2, 2)})
    assert len(decay_groups(model, 0.1)) == 2 and len(decay_groups(model, 0.1, encoder_lr_scale=2.0)) == 3
    scaled = decay_groups(model, 0.0, encoder_lr_scale=2.0)
    assert [len(g["params"]) for g in scaled] == [1, 1, 2] and [g["lr_scale"] for g in scaled] == [2.0, 2.0, 1.0]
