"""The Lovász-softmax term: the surrogate of each class's intersection over union, on rays and 3D points."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest
import torch

from affnerf.errors import AffnerfError
from affnerf.model.field import PointGeometry
from affnerf.model.raymarch import RayOutputs
from affnerf.train.loss import label_lovasz, lovasz_softmax
from affnerf.train.trainer import train


def _mean_jaccard_loss(truth: torch.Tensor, predicted: torch.Tensor) -> float:
    """1 - IoU of each class present in ``truth``, averaged over those classes."""
    losses = []
    for c in torch.unique(truth).tolist():
        t, p = truth == c, predicted == c
        losses.append(1.0 - float((t & p).sum()) / float((t | p).sum()))
    return sum(losses) / len(losses)


def test_on_hard_predictions_it_is_the_mean_jaccard_loss_of_the_classes_present():
    g = torch.Generator().manual_seed(0)
    truth = torch.randint(0, 5, (300,), generator=g)
    truth[truth == 4] = 0  # a class that is predicted but absent does not count
    predicted = torch.where(torch.rand(300, generator=g) < 0.3, torch.randint(0, 5, (300,), generator=g), truth)
    probs = torch.nn.functional.one_hot(predicted, 5).float()
    assert lovasz_softmax(probs, truth).item() == pytest.approx(_mean_jaccard_loss(truth, predicted), abs=1e-6)


def test_a_small_part_counts_as_much_as_the_background():
    truth = torch.zeros(100, dtype=torch.long)
    truth[:2] = 1  # two pixels of a cap among 98 of background
    missed = torch.nn.functional.one_hot(torch.zeros(100, dtype=torch.long), 2).float()  # the cap not found
    ce = torch.nn.functional.nll_loss(torch.log(missed.clamp(min=0.1)), truth).item()
    assert lovasz_softmax(missed, truth).item() > 0.5 > 0.1 > ce  # half the classes lost, 2 % of the pixels


def test_more_probability_on_the_true_class_never_raises_it():
    g = torch.Generator().manual_seed(1)
    logits = torch.randn(64, 4, generator=g, requires_grad=True)
    truth = torch.randint(0, 4, (64,), generator=g)
    probs = torch.softmax(logits, dim=-1)
    probs.retain_grad()
    lovasz_softmax(probs, truth).backward()
    assert bool((probs.grad.gather(1, truth[:, None]) <= 0).all())


def test_rays_are_summed_over_stages_and_points_without_a_target_are_left_out():
    g = torch.Generator().manual_seed(2)
    probs = torch.softmax(torch.randn(20, 3, generator=g), dim=-1)
    labels = torch.randint(0, 3, (20,), generator=g)
    stage = RayOutputs(
        torch.zeros(20, 3), torch.zeros(20), torch.ones(20), probs, torch.zeros(20, 4), torch.zeros(20, 4)
    )
    logits = torch.randn(30, 2, generator=g)
    point_labels = torch.randint(0, 3, (30,), generator=g)  # 0: no target; 1, 2: object classes
    rays, points = label_lovasz([stage, stage], labels, [PointGeometry(torch.ones(30), logits)], point_labels)
    torch.testing.assert_close(rays, 2 * lovasz_softmax(probs, labels))
    keep = point_labels > 0
    torch.testing.assert_close(points, lovasz_softmax(torch.softmax(logits[keep], -1), point_labels[keep] - 1))
    assert label_lovasz([stage], labels)[1].item() == 0.0


def test_training_with_it_logs_the_term_and_a_negative_weight_is_refused(tiny_train_config):
    config = tiny_train_config(steps=6, checkpoint_every=6, lovasz_weight=1.0, points_weight=0.1)
    train(config)
    rows = [json.loads(line) for line in (config.out / "metrics.jsonl").read_text().splitlines()]
    assert all(0.0 <= r["loss/lovasz"] <= 2.0 for r in rows)  # at most 1 a stage, coarse and fine
    with pytest.raises(AffnerfError, match="--lovasz-weight is a weight"):
        train(replace(config, lovasz_weight=-1.0))
