"""The 3D supervision loss: occupancy, affordance and, for a signed-distance field, the truncated distance."""

from __future__ import annotations

import torch

from affnerf.model.field import PointGeometry
from affnerf.train.loss import PointWeights, point_loss, truncated_distance_l1
from affnerf.train.sampler import PointBatch


def _targets(distance: torch.Tensor) -> PointBatch:
    n = len(distance)
    return PointBatch(
        torch.zeros(n, 3),
        torch.zeros(n, dtype=torch.long),
        (distance < 0).float(),
        torch.ones(n, dtype=torch.long),
        distance,
    )


def test_a_point_farther_out_than_the_truncation_only_has_to_be_said_to_be_far():
    target = torch.tensor([0.05, 0.05, -0.01])
    pred = torch.tensor([0.3, 0.02, -0.01], requires_grad=True)
    loss = truncated_distance_l1(pred, target, 0.05)
    loss.backward()
    assert abs(loss.item() - 0.03 / 0.05 / 3) < 1e-6
    assert pred.grad[0] == 0 and pred.grad[1] < 0  # beyond the truncation: no pull; short of it: pushed out


def test_the_distance_term_counts_only_for_signed_distance_fields_at_its_weight():
    target = torch.tensor([0.02, -0.01, 0.05, 0.0])
    density, logits = torch.full((4,), 10.0), torch.zeros(4, 2)
    w = PointWeights(weight=0.5, affordance=1.0, distance=2.0, slab=0.02, truncation=0.05)
    plain = point_loss([PointGeometry(density, logits)], _targets(target), w)
    assert float(plain.distance) == 0.0
    sdf = point_loss([PointGeometry(density, logits, torch.zeros(4))] * 2, _targets(target), w)
    expected = truncated_distance_l1(torch.zeros(4), target, 0.05)
    torch.testing.assert_close(sdf.distance_last, expected)
    torch.testing.assert_close(sdf.distance, 2 * expected)  # summed over the coarse and fine fields
    torch.testing.assert_close(sdf.total - 2 * plain.total, 0.5 * 2.0 * sdf.distance)
