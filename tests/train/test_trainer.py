"""Training behaviour: every parameter learns, losses fall, resuming is exact, bad checkpoints are refused."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import torch
from support import train_argv

from affnerf.cli.main import main
from affnerf.data.dataset import Dataset
from affnerf.errors import AffnerfError
from affnerf.model.affnerf import AffNeRF
from affnerf.train import distributed as dist_utils
from affnerf.train.cache import cached_frames
from affnerf.train.loss import nerf_loss
from affnerf.train.sampler import RaySampler
from affnerf.train.schedule import learning_rate
from affnerf.train.trainer import Trainer, train


def _metrics(run):
    return [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]


def test_one_step_changes_every_parameter_group(train_dataset, tmp_path, tiny_train_config):
    config = tiny_train_config()
    ds = Dataset.open(train_dataset)
    frames = [cached_frames(ds.load_object(e), tmp_path / "c", 1.0, 32) for e in ds.objects(split="train")]
    torch.manual_seed(0)
    model = AffNeRF(config.model, len(ds.affordance_classes))
    before = {k: v.detach().clone() for k, v in model.named_parameters()}
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    batch = RaySampler(frames, 2, 256, 0.5, seed=0).next_batch()
    coarse, fine = model(
        batch.images,
        batch.input_intrinsics,
        batch.input_poses,
        batch.ray_object,
        batch.origins,
        batch.dirs,
        batch.background,
    )
    nerf_loss(coarse, fine, batch.rgb, batch.labels, 0.04).total.backward()
    opt.step()
    groups = {}
    for name, param in model.named_parameters():
        group = ".".join(name.split(".")[: 2 if name.startswith(("shape", "appearance")) else 3])
        groups.setdefault(group, []).append(not torch.equal(param, before[name]))
    unchanged = [g for g, changed in groups.items() if not all(changed)]
    assert not unchanged, unchanged
    assert {
        "shape_encoder.backbone",
        "appearance_encoder.head",
        "renderer.coarse.affordance",
        "renderer.fine.color",
    } <= set(groups)


def test_fifty_steps_reduce_both_losses(tiny_train_config):
    config = tiny_train_config(steps=50, checkpoint_every=50)
    train(config)
    rows = _metrics(config.out)
    first, last = rows[:5], rows[-5:]
    mse0, mse1 = np.mean([r["loss/mse"] for r in first]), np.mean([r["loss/mse"] for r in last])
    ce0, ce1 = np.mean([r["loss/affordance_ce"] for r in first]), np.mean([r["loss/affordance_ce"] for r in last])
    assert mse1 < 0.6 * mse0, (mse0, mse1)
    assert ce1 < 0.6 * ce0, (ce0, ce1)


def test_interrupted_and_resumed_run_ends_with_the_same_weights(tiny_train_config, tmp_path):
    straight = tiny_train_config(out=tmp_path / "straight")
    train(straight)
    halves = tiny_train_config(out=tmp_path / "halves", stop_at=10)
    train(halves)
    assert sorted(p.name for p in (halves.out / "checkpoints").iterdir()) == ["step_00000010.pt"]
    train(replace(halves, stop_at=0, resume=True))
    a = torch.load(straight.out / "checkpoints" / "step_00000020.pt", weights_only=True)
    b = torch.load(halves.out / "checkpoints" / "step_00000020.pt", weights_only=True)
    for key in a["model"]:
        assert torch.equal(a["model"][key], b["model"][key]), key
    assert a["optimizer"]["state"][0]["step"] == b["optimizer"]["state"][0]["step"]


def test_the_optimiser_is_fused_on_the_cpu_and_stays_fused_when_an_unfused_checkpoint_is_resumed(tiny_train_config):
    config = tiny_train_config(stop_at=10)
    train(config)
    path = config.out / "checkpoints" / "step_00000010.pt"
    data = torch.load(path, weights_only=True)
    assert data["optimizer"]["param_groups"][0]["fused"] is True
    for group in data["optimizer"]["param_groups"]:  # as runs before the fused optimiser saved it
        group["fused"] = None
    torch.save(data, path)
    trainer = Trainer(replace(config, stop_at=0, resume=True), dist_utils.setup("cpu"))
    trainer.setup()
    assert trainer.step == 10
    assert all(group["fused"] for group in trainer.state.optimizer.param_groups)


def test_a_model_with_a_shared_coarse_field_trains_its_one_field_with_3d_supervision(tiny_train_config):
    config = tiny_train_config(
        model=replace(tiny_train_config().model, coarse_field="shared"), points_weight=0.1, points_per_object=64
    )
    summary = train(config)
    weights = torch.load(config.out / "checkpoints" / "step_00000020.pt", weights_only=True)["model"]
    assert not any(k.startswith("renderer.fine.") for k in weights)
    assert summary.step == 20 and np.isfinite(summary.scalars["loss/occupancy"])


def test_a_shared_field_model_starts_from_a_two_field_run_with_its_fine_field_and_not_the_other_way(
    tiny_train_config, tmp_path, capsys
):
    two = tiny_train_config(out=tmp_path / "two", stop_at=10)
    train(two)
    saved = torch.load(two.out / "checkpoints" / "step_00000010.pt", weights_only=True)["model"]
    one = tiny_train_config(
        out=tmp_path / "one", model=replace(two.model, coarse_field="shared"), init_from=two.out, steps=5
    )
    trainer = Trainer(one, dist_utils.setup("cpu"))
    trainer.setup()
    loaded = trainer.state.model.state_dict()
    fine = {k: v for k, v in saved.items() if k.startswith("renderer.fine.")}
    assert fine and all(torch.equal(loaded[k.replace(".fine.", ".coarse.", 1)], v) for k, v in fine.items())
    assert all(torch.equal(loaded[k], v) for k, v in saved.items() if k.startswith("shape_encoder."))
    train(replace(one, out=tmp_path / "one-trained", init_from=None))
    back = tiny_train_config(out=tmp_path / "back", init_from=tmp_path / "one-trained", steps=5)
    assert main(train_argv(back)) == 2  # a one-field model has no coarse field to give back
    assert "another configuration (coarse_field 'shared' vs 'own')" in capsys.readouterr().err


def test_a_run_started_from_another_runs_weights_begins_where_that_run_ended_with_a_fresh_schedule(
    tiny_train_config, tmp_path, capsys
):
    first = tiny_train_config(out=tmp_path / "first", steps=10)
    train(first)
    ended = torch.load(first.out / "checkpoints" / "step_00000010.pt", weights_only=True)["model"]
    second = tiny_train_config(out=tmp_path / "second", steps=4, checkpoint_every=4, init_from=first.out)
    trainer = Trainer(second, dist_utils.Context(rank=0, world=1, device=torch.device("cpu")))
    trainer.setup()
    for key, value in trainer.state.model.state_dict().items():
        assert torch.equal(value, ended[key]), key
    assert trainer.step == 0 and not trainer.state.optimizer.state_dict()["state"]
    assert trainer.train_iteration(0)["train/lr"] == second.optim.lr  # its own schedule, from the start
    fresh = Trainer(replace(second, out=tmp_path / "fresh", init_from=None), trainer.ctx)
    fresh.setup()
    assert not all(torch.equal(v, ended[k]) for k, v in fresh.state.model.state_dict().items())
    wider = replace(second, out=tmp_path / "wider", model=replace(second.model, field_width=48))
    assert main(train_argv(wider)) == 2
    assert "checkpoint is from another configuration (field_width 32 vs 48)" in capsys.readouterr().err
    assert main(train_argv(replace(wider, init_from=tmp_path / "nothing"))) == 2


def test_a_checkpoint_older_than_a_model_field_counts_as_having_its_default(tiny_train_config, tmp_path, capsys):
    first = tiny_train_config(out=tmp_path / "first", steps=2, checkpoint_every=2)
    train(first)
    path = first.out / "checkpoints" / "step_00000002.pt"
    data = torch.load(path, weights_only=False)
    del data["model_config"]["geometry"]  # as in checkpoints made before the field existed (the shipped model's)
    torch.save(data, path)
    second = tiny_train_config(out=tmp_path / "second", steps=1, checkpoint_every=1, init_from=path)
    assert main(train_argv(second)) == 0
    sdf = replace(second, out=tmp_path / "sdf", model=replace(second.model, geometry="sdf"))
    assert main(train_argv(sdf)) == 2
    assert "checkpoint is from another configuration (geometry 'density' vs 'sdf')" in capsys.readouterr().err


def test_init_from_grows_a_concatenating_field_into_film_and_not_back(tiny_train_config, tmp_path, capsys):
    first = tiny_train_config(out=tmp_path / "concat", steps=6)
    train(first)
    ended = torch.load(first.out / "checkpoints" / "step_00000006.pt", weights_only=True)["model"]
    film = replace(first, out=first.out.parent / "film", steps=4, init_from=first.out)
    film = replace(film, model=replace(film.model, conditioning="film"))
    trainer = Trainer(film, dist_utils.Context(rank=0, world=1, device=torch.device("cpu")))
    trainer.setup()
    grown = trainer.state.model.state_dict()
    new_keys = sorted(set(grown) - set(ended))
    assert new_keys and all(".film." in key for key in new_keys)
    assert all(torch.equal(grown[key], ended[key]) for key in ended)
    assert all(not grown[key].any() for key in new_keys)  # zero modulation: the same function as the source
    train(film)
    back = replace(first, out=first.out.parent / "back", steps=2, init_from=film.out)
    assert main(train_argv(back)) == 2
    assert "conditioning 'film' vs 'concat'" in capsys.readouterr().err


def test_init_from_grows_a_pixel_labelling_head_and_training_logs_its_loss(tiny_train_config, tmp_path):
    first = tiny_train_config(out=tmp_path / "plain", steps=4)
    train(first)
    ended = torch.load(first.out / "checkpoints" / "step_00000004.pt", weights_only=True)["model"]
    labelled = replace(first, out=tmp_path / "labelled", steps=4, init_from=first.out)
    labelled = replace(labelled, model=replace(labelled.model, view_affordance_weight=0.1))
    trainer = Trainer(labelled, dist_utils.Context(rank=0, world=1, device=torch.device("cpu")))
    trainer.setup()
    grown = trainer.state.model.state_dict()
    assert sorted(set(grown) - set(ended)) == ["shape_encoder.label_head.bias", "shape_encoder.label_head.weight"]
    assert all(torch.equal(grown[key], ended[key]) for key in ended)
    train(labelled)
    losses = [m["loss/view_affordance"] for m in _metrics(labelled.out)]
    assert len(losses) == 4 and all(v > 0 for v in losses) and losses[-1] < losses[0]


def test_init_from_may_change_the_encoders_crop_side_and_trains_at_the_new_one(tiny_train_config, tmp_path):
    first = tiny_train_config(out=tmp_path / "small_crops", steps=2, checkpoint_every=2)
    train(first)
    ended = torch.load(first.out / "checkpoints" / "step_00000002.pt", weights_only=True)["model"]
    side = first.model.encoder_resolution + 16
    larger = replace(first, out=tmp_path / "larger_crops", steps=2, init_from=first.out)
    larger = replace(larger, model=replace(larger.model, encoder_resolution=side))
    trainer = Trainer(larger, dist_utils.Context(rank=0, world=1, device=torch.device("cpu")))
    trainer.setup()
    assert all(torch.equal(value, ended[key]) for key, value in trainer.state.model.state_dict().items())
    assert trainer.train_iteration(0)["loss/total"] > 0
    train(replace(larger, out=tmp_path / "larger_run"))
    saved = torch.load(tmp_path / "larger_run" / "checkpoints" / "step_00000002.pt", weights_only=False)
    assert saved["model_config"]["encoder_resolution"] == side


def test_train_iteration_takes_exactly_one_step_and_hooks_do_the_rest(tiny_train_config):
    config = tiny_train_config(steps=4, checkpoint_every=2)
    trainer = Trainer(config, dist_utils.Context(rank=0, world=1, device=torch.device("cpu")))
    trainer.setup()
    before = {k: v.detach().clone() for k, v in trainer.state.model.named_parameters()}
    outputs = trainer.train_iteration(0)
    assert set(outputs) == {"loss/total", "loss/mse", "loss/affordance_ce", "train/affordance_accuracy", "train/lr"}
    assert all(v.ndim == 0 and not v.requires_grad for k, v in outputs.items() if k != "train/lr")
    assert outputs["train/lr"] == config.optim.lr
    assert trainer.state.optimizer.state_dict()["state"][0]["step"] == 1 and trainer.step == 0
    assert any(not torch.equal(p, before[k]) for k, p in trainer.state.model.named_parameters())
    assert not (config.out / "metrics.jsonl").read_text() and not any((config.out / "checkpoints").glob("*.pt"))
    trainer.step = 1
    trainer.after_iteration(outputs, out_of_time=True)  # logs (log_every 1) and checkpoints (out of time)
    assert [json.loads(line)["step"] for line in (config.out / "metrics.jsonl").read_text().splitlines()] == [1]
    assert (config.out / "checkpoints" / "step_00000001.pt").is_file()
    summary = trainer.train()
    assert summary.step == 4 and summary.scalars["train/lr"] == pytest.approx(learning_rate(config, 3))
    assert sorted(p.name for p in (config.out / "checkpoints").iterdir())[-1] == "step_00000004.pt"


def test_existing_run_needs_resume_and_keeps_its_checkpoints(tiny_train_config):
    config = tiny_train_config(steps=10)
    train(config)
    with pytest.raises(AffnerfError, match="already holds a run"):
        train(config)
    assert (config.out / "checkpoints" / "step_00000010.pt").is_file()


def _cli(config, *extra):
    model = replace(config.model, num_coarse=8, num_fine=8)
    run = replace(config, steps=10, rays_per_step=64, checkpoint_every=5, val_every=0, model=model)
    return train_argv(run, *extra)


def test_checkpoint_of_another_configuration_is_a_clear_error(tiny_train_config, capsys):
    config = tiny_train_config()
    assert main(_cli(config)) == 0
    capsys.readouterr()
    args = _cli(config, "--steps", "20", "--resume")
    args[args.index("--model.field-width") + 1] = "48"
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert "step_00000010.pt: checkpoint is from another configuration (field_width 32 vs 48)" in err


def test_corrupt_checkpoint_is_a_clear_error(tiny_train_config, capsys):
    config = tiny_train_config()
    assert main(_cli(config)) == 0
    capsys.readouterr()
    last = config.out / "checkpoints" / "step_00000010.pt"
    last.write_bytes(last.read_bytes()[:1000])
    assert main(_cli(config, "--steps", "20", "--resume")) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "step_00000010.pt: not a readable checkpoint" in err


def test_run_folder_reproduces_its_config(tiny_train_config, tmp_path, capsys):
    config = tiny_train_config()
    assert main(_cli(config)) == 0
    again = tmp_path / "again"
    assert main(["train", "--config-file", str(config.out / "config.json"), "--out", str(again)]) == 0
    a, b = json.loads((config.out / "config.json").read_text()), json.loads((again / "config.json").read_text())
    assert {k: v for k, v in a.items() if k != "out"} == {k: v for k, v in b.items() if k != "out"}
    wa = torch.load(config.out / "checkpoints" / "step_00000010.pt", weights_only=True)["model"]
    wb = torch.load(again / "checkpoints" / "step_00000010.pt", weights_only=True)["model"]
    assert all(torch.equal(wa[k], wb[k]) for k in wa)


def test_validation_renders_and_scores_held_out_objects(trained_runs, train_dataset):
    from affnerf.predict.loading import load_model
    from affnerf.train.validate import validate

    loaded = load_model(trained_runs["affnerf"])
    ds = Dataset.open(train_dataset)
    result = validate(loaded.model, [ds.load_object(e) for e in ds.objects(split="val")], 0.5, views_per_object=2)
    assert len(result.images) == 2 and result.images[0].shape == (15, 5 * 20, 3)
    assert 0 <= result.miou <= 1 and 0 <= result.accuracy <= 1 and result.psnr > 0


def test_init_from_grows_a_mean_pooling_shape_encoder_into_keypoints_with_the_same_codes(tiny_train_config, tmp_path):
    first = tiny_train_config(out=tmp_path / "mean", steps=4)
    train(first)
    ended = torch.load(first.out / "checkpoints" / "step_00000004.pt", weights_only=True)["model"]
    grown_config = replace(first, out=tmp_path / "keypoints", steps=2, init_from=first.out)
    grown_config = replace(grown_config, model=replace(grown_config.model, shape_pooling="keypoints"))
    trainer = Trainer(grown_config, dist_utils.Context(rank=0, world=1, device=torch.device("cpu")))
    trainer.setup()
    grown = trainer.state.model.state_dict()
    head = "shape_encoder.head.weight"
    assert set(grown) == set(ended) and grown[head].shape[1] > ended[head].shape[1]
    assert (
        torch.equal(grown[head][:, : ended[head].shape[1]], ended[head])
        and not grown[head][:, ended[head].shape[1] :].any()
    )
    assert all(torch.equal(grown[key], ended[key]) for key in ended if key != head)
    model = trainer.state.model.eval()
    source = Trainer(replace(first, out=tmp_path / "again", init_from=first.out), trainer.ctx)
    source.setup()
    crops = torch.rand(2, 3, first.model.encoder_resolution, first.model.encoder_resolution)
    with torch.no_grad():
        torch.testing.assert_close(model.encode(crops).shape, source.state.model.eval().encode(crops).shape)
    assert main(train_argv(grown_config)) == 0
