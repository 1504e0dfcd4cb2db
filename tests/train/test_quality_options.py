"""Training options beyond the paper (mask and depth losses, class-balanced CE, input jitter, FiLM): logged,
effective, resumable, and off in the paper preset."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import torch
from support import straight_and_resumed_weights

from affnerf.errors import AffnerfError
from affnerf.train.cache import cached_frames
from affnerf.train.config import PAPER
from affnerf.train.loss import class_weights, code_consistency, termination_l1
from affnerf.train.trainer import label_counts, train

ALL_ON = {
    "mask_weight": 0.1,
    "depth_weight": 1.0,
    "termination_weight": 1.0,
    "lovasz_weight": 1.0,
    "affordance_balance": 0.5,
    "input_jitter": 1.0,
    "view_consistency_weight": 0.1,
}


def _metrics(run):
    return [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]


def test_the_paper_preset_keeps_the_papers_loss_and_model():
    assert PAPER.mask_weight == PAPER.depth_weight == PAPER.affordance_balance == PAPER.input_jitter == 0
    assert PAPER.termination_weight == PAPER.view_consistency_weight == 0
    assert PAPER.model.conditioning == "concat"


def test_mask_and_depth_terms_are_logged_and_fall(tiny_train_config):
    config = tiny_train_config(steps=30, checkpoint_every=30, mask_weight=1.0, depth_weight=1.0)
    config = replace(config, optim=replace(config.optim, lr=3e-3))
    train(config)
    rows = _metrics(config.out)
    assert all({"loss/mask", "loss/depth"} <= set(r) for r in rows)
    first, last = np.mean([r["loss/mask"] for r in rows[:5]]), np.mean([r["loss/mask"] for r in rows[-5:]])
    assert last < 0.8 * first, (first, last)


def test_termination_term_is_logged_and_pulls_weight_onto_the_surface(tiny_train_config, tmp_path):
    ends = {}
    for name, weight in (("mask_only", 0.0), ("with_termination", 3.0)):
        config = tiny_train_config(out=tmp_path / name, steps=40, checkpoint_every=40, mask_weight=1.0)
        config = replace(config, termination_weight=weight, optim=replace(config.optim, lr=3e-3))
        train(config)
        rows = _metrics(config.out)
        assert all("loss/termination" in r for r in rows)  # logged whenever a ray geometry term is on
        ends[name] = np.mean([r["loss/termination"] for r in rows[-10:]])
    assert ends["with_termination"] < ends["mask_only"], ends


def test_termination_costs_weight_off_the_surface_and_never_rewards_adding_it():
    t = torch.tensor([[0.3, 0.4, 0.5]])
    surface = torch.tensor([0.4])
    on = termination_l1(torch.tensor([[0.0, 1.0, 0.0]]), t, surface)
    halo = termination_l1(torch.tensor([[0.3, 0.7, 0.0]]), t, surface)
    empty = termination_l1(torch.zeros(1, 3), t, surface)
    assert float(on) == 0.0 == float(empty) and float(halo) > 0.0
    weights = torch.tensor([[0.2, 0.3, 0.1]], requires_grad=True)
    termination_l1(weights, t, surface).backward()
    assert bool((weights.grad >= 0).all())  # more weight anywhere never lowers it (the depth L1 rewards it)


def test_cached_depth_matches_the_dataset_and_balanced_weights_favour_rare_classes(tiny_train_config, train_dataset):
    from affnerf.data.dataset import Dataset

    config = tiny_train_config()
    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects("train")[0])
    frames = cached_frames(obj, config.cache_dir, 1.0, 32)
    np.testing.assert_allclose(np.asarray(frames.depth[0], np.float32), obj.depth(0), atol=2e-3 * obj.depth(0).max())
    counts = label_counts([frames], len(ds.affordance_classes))
    assert int(counts.sum()) == frames.labels.size
    w = class_weights(counts, 0.5)
    seen = counts > 0
    rare, common = int(torch.argmin(torch.where(seen, counts, torch.inf))), int(torch.argmax(counts))
    assert w[rare] > w[common] and bool((w[~seen] == 0).all())


def test_a_run_with_every_option_resumes_to_the_same_weights(tiny_train_config, tmp_path):
    straight = tiny_train_config(out=tmp_path / "straight", **ALL_ON)
    straight = replace(straight, model=replace(straight.model, conditioning="film"))
    a, b = straight_and_resumed_weights(straight, stop_at=10)
    assert any(k.endswith("film.weight") for k in a)
    assert all(torch.equal(a[k], b[k]) for k in a)


def test_a_triplane_run_resumes_to_the_same_weights(tiny_train_config, tmp_path):
    straight = tiny_train_config(out=tmp_path / "straight", points_weight=0.1)
    model = replace(straight.model, conditioning="triplane", plane_resolution=8, plane_channels=4)
    a, b = straight_and_resumed_weights(replace(straight, model=model), stop_at=10)
    assert any(k.startswith("planes.") for k in a)
    assert all(torch.equal(a[k], b[k]) for k in a)


def test_code_consistency_is_zero_for_agreeing_views_and_blind_to_the_codes_scale():
    g = torch.Generator().manual_seed(0)
    first = torch.randn(6, 8, generator=g)
    second = first + 0.3 * torch.randn(6, 8, generator=g)
    assert code_consistency(first, first).item() == 0.0
    near = code_consistency(first, second)
    assert near > 0
    assert torch.isclose(code_consistency(10 * first, 10 * second), near, rtol=1e-5)  # shrinking cannot lower it
    assert code_consistency(first, first + 0.6 * (second - first)) < near
    pulled = first.clone().requires_grad_(True)
    code_consistency(pulled, second).backward()
    step = pulled - 0.1 * pulled.grad  # the gradient moves the first view's codes towards the second's
    assert code_consistency(step.detach(), second) < near


def test_view_consistency_term_is_logged_and_falls(tiny_train_config):
    config = tiny_train_config(steps=40, checkpoint_every=40, view_consistency_weight=1.0)
    train(replace(config, optim=replace(config.optim, lr=3e-3)))
    rows = _metrics(config.out)
    assert all("loss/view_consistency" in r for r in rows)
    first = np.mean([r["loss/view_consistency"] for r in rows[:5]])
    last = np.mean([r["loss/view_consistency"] for r in rows[-5:]])
    assert last < 0.7 * first, (first, last)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [({"objects_per_step": 1}, "at least 2 objects"), ({"model": "pixelnerf"}, "global codes")],
)
def test_view_consistency_refuses_what_it_cannot_compare(tiny_train_config, overrides, message):
    config = tiny_train_config(view_consistency_weight=0.1)
    if overrides.get("model"):
        overrides = {"model": replace(config.model, kind=overrides["model"])}
    with pytest.raises(AffnerfError, match=message):
        train(replace(config, **overrides))


def test_the_pixel_labelling_head_refuses_jittered_crops(tiny_train_config):
    config = tiny_train_config(input_jitter=1.0)
    with pytest.raises(AffnerfError, match="input-jitter 0"):
        train(replace(config, model=replace(config.model, view_affordance_weight=0.1)))


def test_surface_samples_are_logged_falling_to_zero_and_resume_to_the_same_weights(tiny_train_config, tmp_path):
    config = tiny_train_config(out=tmp_path / "guided", steps=20, log_every=1, surface_sample_share=0.5)
    train(replace(config, surface_sample_until=0.5))
    shares = [r["train/surface_sample_share"] for r in _metrics(config.out)]
    assert shares[0] > shares[4] > 0 and shares[-1] == 0.0
    straight = tiny_train_config(out=tmp_path / "straight", surface_sample_share=0.5)
    a, b = straight_and_resumed_weights(straight, stop_at=10)
    assert all(torch.equal(a[k], b[k]) for k in a)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"surface_sample_share": 1.5}, "in \\(0, 1\\]"),
        ({"surface_sample_until": 0.0}, "in \\(0, 1\\]"),
        ({"surface_sample_sigma": -0.01}, "sigma >= 0"),
        ({"num_fine": 0}, "needs fine samples"),
        ({"kind": "gsnerf"}, "samples each point on its own"),
    ],
)
def test_surface_samples_refuse_what_they_cannot_move(tiny_train_config, overrides, message):
    config = tiny_train_config(surface_sample_share=overrides.pop("surface_sample_share", 0.5))
    model = {k: overrides.pop(k) for k in ("num_fine", "kind") if k in overrides}
    with pytest.raises(AffnerfError, match=message):
        train(replace(config, model=replace(config.model, **model), **overrides))


def test_variational_codes_log_their_kl_and_resume_to_the_same_weights(tiny_train_config, tmp_path):
    config = tiny_train_config(out=tmp_path / "kl", steps=6, log_every=1)
    variational = replace(config.model, code_kl_weight=0.01)
    train(replace(config, model=variational))
    kls = [r["loss/code_kl"] for r in _metrics(config.out)]
    assert len(kls) == 6 and all(k > 0 for k in kls)
    straight = tiny_train_config(out=tmp_path / "straight")
    a, b = straight_and_resumed_weights(replace(straight, model=replace(straight.model, code_kl_weight=0.01)), 10)
    assert any("log_var_head" in k for k in a) and all(torch.equal(a[k], b[k]) for k in a)
