"""Training with 3D supervision: the terms are logged and fall, resuming stays exact, and weight 0 is the paper's
loss step for step."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import torch
from support import straight_and_resumed_weights

from affnerf.data.dataset import Dataset
from affnerf.errors import AffnerfError
from affnerf.model.registry import build_model
from affnerf.train import distributed as dist_utils
from affnerf.train.config import PAPER, SMALL
from affnerf.train.loss import nerf_loss
from affnerf.train.options import check_options
from affnerf.train.sampler import RaySampler
from affnerf.train.state import make_optimizer
from affnerf.train.trainer import Trainer, train

CPU = dist_utils.Context(rank=0, world=1, device=torch.device("cpu"))


def _metrics(run):
    return [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]


def test_the_paper_preset_leaves_points_off_and_small_turns_them_on():
    assert PAPER.points_weight == 0 and SMALL.points_weight > 0


def test_points_are_logged_and_the_occupancy_loss_falls(tiny_train_config, train_dataset):
    config = tiny_train_config(steps=30, checkpoint_every=30, points_weight=1.0, points_per_object=512)
    config = replace(config, optim=replace(config.optim, lr=3e-3))  # densities of ~100 /m take many small steps
    train(config)
    rows = _metrics(config.out)
    assert len(rows) == 30 and all({"loss/occupancy", "loss/point_affordance"} <= set(r) for r in rows)
    occ0, occ1 = np.mean([r["loss/occupancy"] for r in rows[:5]]), np.mean([r["loss/occupancy"] for r in rows[-5:]])
    aff0 = np.mean([r["loss/point_affordance"] for r in rows[:5]])
    aff1 = np.mean([r["loss/point_affordance"] for r in rows[-5:]])
    assert occ1 < 0.7 * occ0, (occ0, occ1)  # measured: 1.46 -> 0.73
    assert aff1 < 0.7 * aff0, (aff0, aff1)  # measured: 2.2 -> 0.85
    ds = Dataset.open(train_dataset)
    train_ids = sorted(f"{e.id}.points" for e in ds.objects(split="train"))
    assert sorted(p.name for p in config.cache_dir.glob("*.points")) == train_ids
    ckpt = torch.load(config.out / "checkpoints" / "step_00000030.pt", weights_only=False)
    assert "points" in ckpt["rank_states"][0] and ckpt["train_config"]["points_weight"] == 1.0


def test_a_signed_distance_field_logs_its_distance_loss_and_learns_it(tiny_train_config):
    config = tiny_train_config(steps=30, checkpoint_every=30, points_weight=1.0, points_per_object=512)
    config = replace(config, model=replace(config.model, geometry="sdf"), optim=replace(config.optim, lr=3e-3))
    train(config)
    rows = _metrics(config.out)
    assert all({"loss/occupancy", "loss/point_distance"} <= set(r) for r in rows)
    d0, d1 = (
        np.mean([r["loss/point_distance"] for r in rows[:5]]),
        np.mean([r["loss/point_distance"] for r in rows[-5:]]),
    )
    assert d1 < 0.7 * d0, (d0, d1)
    ckpt = torch.load(config.out / "checkpoints" / "step_00000030.pt", weights_only=False)
    assert any(key.endswith("log_beta") for key in ckpt["model"])


def test_interrupted_and_resumed_run_with_points_ends_with_the_same_weights(tiny_train_config, tmp_path):
    straight = tiny_train_config(out=tmp_path / "straight", points_weight=0.5, points_per_object=256)
    a, b = straight_and_resumed_weights(straight, stop_at=10)
    assert all(torch.equal(a[k], b[k]) for k in a)


def test_weight_zero_takes_the_papers_step_bit_for_bit(tiny_train_config, train_dataset):
    """Three steps of the trainer against the paper's step written out by hand (the model's own forward and
    nerf_loss): the same losses and the same weights, and no point is drawn or cached."""
    config = tiny_train_config(steps=3, points_per_object=4096)
    trainer = Trainer(config, CPU)
    trainer.setup()
    assert trainer.state.points is None and not list(config.cache_dir.glob("*.points"))
    assert "points" not in trainer.state.rank_state()
    torch.manual_seed(config.seed)
    model = build_model(config.model, len(Dataset.open(train_dataset).affordance_classes))
    optimizer = make_optimizer(model, config.optim.lr, torch.device("cpu"))  # the trainer's (fused) Adam
    sampler = RaySampler(trainer.state.sampler.objects, config.objects_per_step, config.rays_per_step, 0.5, config.seed)
    generator = torch.Generator().manual_seed(config.seed * 1000)
    for step in range(3):
        outputs = trainer.train_iteration(step)
        assert "loss/occupancy" not in outputs
        batch = sampler.next_batch()
        for group in optimizer.param_groups:
            group["lr"] = outputs["train/lr"]
        args = (batch.images, batch.input_intrinsics, batch.input_poses, batch.ray_object, batch.origins)
        coarse, fine = model(*args, batch.dirs, batch.background, True, generator)
        terms = nerf_loss(coarse, fine, batch.rgb, batch.labels, config.affordance_weight)
        optimizer.zero_grad(set_to_none=True)
        terms.total.backward()
        optimizer.step()
        assert torch.equal(outputs["loss/total"], terms.total.detach())
        assert torch.equal(outputs["loss/mse"], terms.mse_fine.detach())
    theirs = dict(model.named_parameters())
    assert all(torch.equal(p, theirs[k]) for k, p in trainer.state.model.named_parameters())


def test_points_without_points_per_object_are_refused(tiny_train_config):
    config = tiny_train_config(points_weight=1.0, points_per_object=0)
    with pytest.raises(AffnerfError, match="points-per-object >= 1"):
        train(config)


def test_a_part_balance_outside_zero_to_one_is_refused_only_with_points():
    with pytest.raises(AffnerfError, match="point-part-balance in"):
        check_options(replace(SMALL, point_part_balance=1.5))
    check_options(replace(SMALL, point_part_balance=1.0))
    check_options(replace(SMALL, points_weight=0.0, point_part_balance=1.5))  # no points: nothing to balance


def test_the_configs_uniform_share_is_the_point_sets_default():
    from affnerf.train.points import UNIFORM_SHARE

    assert SMALL.point_uniform_share == UNIFORM_SHARE  # the default keeps the cached point sets' signature


def test_a_uniform_share_outside_zero_to_one_is_refused():
    with pytest.raises(AffnerfError, match="point-uniform-share in"):
        check_options(replace(SMALL, point_uniform_share=-0.1))
    check_options(replace(SMALL, point_uniform_share=0.0))


def test_a_points_weight_schedule_is_logged_and_goes_from_start_to_final(tiny_train_config):
    config = tiny_train_config(steps=10, checkpoint_every=10, points_weight=1.0, points_weight_final=0.0)
    train(config)
    mus = [r["train/points_weight"] for r in _metrics(config.out)]
    assert mus[0] == pytest.approx(1.0) and mus[-1] == pytest.approx(0.1)  # step 9 of 10
    assert all(a > b for a, b in zip(mus, mus[1:], strict=False))


def test_a_points_weight_final_without_points_is_refused():
    with pytest.raises(AffnerfError, match="--points-weight-final"):
        check_options(replace(SMALL, points_weight=0.0, points_weight_final=0.5))
    check_options(replace(SMALL, points_weight_final=0.5))
