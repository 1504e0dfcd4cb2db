"""The average of the weights (``--optim.ema-decay``): what it averages, where it is saved, who uses it."""

from __future__ import annotations

from dataclasses import replace

import pytest
import torch
from support import train_argv

from affnerf.cli.main import main
from affnerf.predict.loading import load_model
from affnerf.predict.shipped import export_for_inference
from affnerf.train import distributed as dist_utils
from affnerf.train.ema import WeightAverage, ema_rate
from affnerf.train.trainer import Trainer, train


def test_the_average_follows_the_weights_at_its_rate_and_keeps_buffers_as_they_are():
    model = torch.nn.Sequential(torch.nn.Linear(2, 2), torch.nn.BatchNorm1d(2))
    average = WeightAverage(model, 0.5)
    start = model[0].weight.detach().clone()
    with torch.no_grad():
        model[0].weight.add_(1.0)
        model[1].running_mean.fill_(3.0)
    for _ in range(20):  # past the warm-up cap, the rate is 1 - 0.5
        average.update(model)
    state = average.state_dict(model)
    torch.testing.assert_close(state["0.weight"], start + 1.0, atol=1e-5, rtol=0)
    assert torch.equal(state["1.running_mean"], torch.full((2,), 3.0))
    assert ema_rate(0.5, 100) == 0.5 and ema_rate(0.999, 1) > 0.5  # the first updates take the weights fast
    with torch.no_grad():
        model[0].weight.add_(10.0)
    average.update(model)
    torch.testing.assert_close(average.state_dict(model)["0.weight"], start + 6.0, atol=1e-5, rtol=0)
    with pytest.raises(ValueError, match="decay in"):
        WeightAverage(model, 1.0)


def test_a_decay_outside_zero_to_one_is_one_clear_line(tiny_train_config, capsys):
    config = tiny_train_config()
    assert main(train_argv(config, "--optim.ema-decay", "1.5")) == 2
    assert "--optim.ema-decay is 0 (no average) or in (0, 1), not 1.5" in capsys.readouterr().err
    assert not (config.out / "checkpoints").exists()


def test_a_run_with_an_average_saves_it_resumes_it_exactly_and_inference_uses_it(tiny_train_config, tmp_path):
    config = tiny_train_config(optim=replace(tiny_train_config().optim, ema_decay=0.9))
    train(config)
    data = torch.load(config.out / "checkpoints" / "step_00000020.pt", weights_only=True)
    assert data["ema_updates"] == 20 and data["ema"].keys() == data["model"].keys()
    differ = [k for k in data["model"] if not torch.equal(data["model"][k], data["ema"][k])]
    assert differ  # the average lags behind the trained weights
    loaded = load_model(config.out).model.state_dict()
    assert all(torch.equal(loaded[k], data["ema"][k]) for k in differ)
    slim = torch.load(export_for_inference(config.out, tmp_path / "slim.pt"), weights_only=True)
    assert "ema" not in slim and all(torch.equal(slim["model"][k], data["ema"][k]) for k in data["ema"])

    halves = replace(config, out=tmp_path / "halves", stop_at=10)
    train(halves)
    train(replace(halves, stop_at=0, resume=True))
    resumed = torch.load(halves.out / "checkpoints" / "step_00000020.pt", weights_only=True)
    assert all(torch.equal(resumed["ema"][k], data["ema"][k]) for k in data["ema"])

    further = tiny_train_config(out=tmp_path / "further", init_from=config.out, steps=5, optim=config.optim)
    trainer = Trainer(further, dist_utils.setup("cpu"))
    trainer.setup()  # starts from the average, and so does its own average
    started = trainer.state.model.state_dict()
    assert all(torch.equal(started[k], data["ema"][k]) for k in differ)
    assert trainer.state.ema is not None and trainer.state.ema.updates == 0
    assert all(torch.equal(trainer.state.ema.state_dict(trainer.state.model)[k], data["ema"][k]) for k in differ)
