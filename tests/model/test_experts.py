"""Weight experts: grouped products, fresh layers that equal one plain layer, order-free outputs, the router's
loss and experts that make objects differ once they differ."""

from __future__ import annotations

from dataclasses import replace

import pytest
import torch
from support import TINY_MODEL

from affnerf.model.experts import ExpertLinear, Router, group_order, grouped_linear
from affnerf.model.field import ConditionalField, ObjectCodes
from affnerf.model.registry import build_model


@pytest.mark.parametrize("counts", [[3, 3, 3], [1, 4, 0, 2], [5]])
def test_grouped_products_equal_each_rows_own_objects_product(counts):
    weight, x = torch.randn(len(counts), 5, 4), torch.randn(sum(counts), 4)
    obj = torch.repeat_interleave(torch.arange(len(counts)), torch.tensor(counts))
    expected = torch.stack([weight[b] @ row for b, row in zip(obj.tolist(), x, strict=True)])
    torch.testing.assert_close(grouped_linear(x, weight, counts), expected)
    assert grouped_linear(x[:0], weight, [0] * len(counts)).shape == (0, 5)


def test_group_order_sorts_only_what_is_not_grouped():
    assert group_order(torch.tensor([0, 0, 1, 2]), 3) == (None, [2, 1, 1])
    order, counts = group_order(torch.tensor([2, 0, 1, 0]), 4)
    assert order.tolist() == [1, 3, 2, 0] and counts == [2, 1, 1, 0]


def test_a_fresh_expert_layer_is_one_linear_layer_under_any_mixture():
    torch.manual_seed(3)
    plain = torch.nn.Linear(6, 4)
    torch.manual_seed(3)
    experts = ExpertLinear(6, 4, experts=5)
    mix = torch.softmax(torch.randn(3, 5), dim=-1)
    weight, bias = experts.mixed(mix)
    torch.testing.assert_close(weight, plain.weight.expand(3, 4, 6))
    torch.testing.assert_close(bias, plain.bias.expand(3, 4))


def _codes(points_per_object: list[int], experts: int, code_dim: int = 8) -> ObjectCodes:
    obj = torch.repeat_interleave(torch.arange(len(points_per_object)), torch.tensor(points_per_object))
    pick = torch.nn.functional.one_hot(obj, len(points_per_object)).float()
    mix = torch.softmax(3 * torch.randn(len(points_per_object), experts), dim=-1)
    return ObjectCodes(torch.randn(len(points_per_object), code_dim), pick, mix)


def test_a_fresh_expert_field_computes_the_plain_field_and_differs_once_its_experts_do():
    torch.manual_seed(0)
    plain = ConditionalField(num_classes=4, code_dim=8, width=16, depth=4, sdf=True)
    torch.manual_seed(0)
    field = ConditionalField(num_classes=4, code_dim=8, width=16, depth=4, sdf=True, experts=3)
    codes, points = _codes([10, 6], experts=3), torch.rand(16, 3) - 0.5
    torch.testing.assert_close(field.supervised(points, codes).logits, plain.supervised(points, codes).logits)
    with torch.no_grad():
        for layer in field.trunk_layers:
            layer.weight.add_(0.3 * torch.randn_like(layer.weight))
    code, pick = codes.table[:1], torch.ones(16, 1)
    first = field.trunk(points, ObjectCodes(code, pick, torch.eye(3)[:1]))
    second = field.trunk(points, ObjectCodes(code, pick, torch.eye(3)[1:2]))
    assert (first - second).abs().max() > 1e-3  # the same code and points through another expert
    halfway = field.trunk(points, ObjectCodes(code, pick, torch.tensor([[0.5, 0.5, 0.0]])))
    assert not torch.allclose(halfway, first) and not torch.allclose(halfway, second)


def test_expert_outputs_do_not_depend_on_the_points_order():
    torch.manual_seed(1)
    field = ConditionalField(num_classes=4, code_dim=8, width=16, depth=4, experts=3)
    with torch.no_grad():
        for layer in field.trunk_layers:
            layer.weight.add_(0.3 * torch.randn_like(layer.weight))
    codes, points = _codes([7, 5, 4], experts=3), torch.rand(16, 3) - 0.5
    perm = torch.randperm(16)
    shuffled = ObjectCodes(codes.table, codes.pick[perm], codes.mix)
    torch.testing.assert_close(field.trunk(points[perm], shuffled), field.trunk(points, codes)[perm])


def test_an_expert_field_refuses_codes_without_a_mixture_and_film():
    field = ConditionalField(num_classes=4, code_dim=8, width=16, depth=2, experts=2)
    with pytest.raises(ValueError, match="mixture"):
        field.trunk(torch.rand(4, 3), torch.randn(4, 8))
    with pytest.raises(ValueError, match="FiLM"):
        ConditionalField(num_classes=4, code_dim=8, width=16, depth=2, experts=2, film=True)


def test_the_router_loss_needs_families_and_reaches_the_router_and_the_encoder():
    torch.manual_seed(0)
    model = build_model(replace(TINY_MODEL, experts=2), num_classes=5)
    images = torch.rand(2, 1, 3, 32, 32)
    encoding = model.encode_views(images, torch.zeros(2, 1, 4), torch.eye(4).expand(2, 1, 4, 4))
    assert "loss/router" not in model.auxiliary_losses(encoding)
    loss = model.auxiliary_losses(encoding, object_families=torch.tensor([0, 1]))["loss/router"]
    loss.backward()
    assert model.router.linear.weight.grad.abs().sum() > 0
    assert model.shape_encoder.head.weight.grad.abs().sum() > 0
    torch.testing.assert_close(Router(4, 3)(torch.randn(2, 4)).sum(dim=-1), torch.ones(2))
