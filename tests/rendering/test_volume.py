"""Volume rendering against hand-computed values."""

from __future__ import annotations

import math

import torch

from affnerf.rendering.volume import (
    accumulate,
    composite,
    render_affordance,
    render_depth,
    sample_deltas,
    weights_from_density,
)


def test_single_opaque_sample_takes_all_the_weight():
    sigma = torch.tensor([[0.0, 0.0, 1e6, 0.0, 3.0]])
    t = torch.tensor([[0.1, 0.2, 0.3, 0.4, 0.5]])
    w, trans = weights_from_density(sigma, sample_deltas(t, torch.tensor([0.6])))
    torch.testing.assert_close(w, torch.tensor([[0.0, 0.0, 1.0, 0.0, 0.0]]))
    assert trans.item() == 0.0
    assert math.isclose(render_depth(w, t).item(), 0.3, rel_tol=1e-6)
    colors = torch.tensor([[[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [1.0, 1, 1], [0.5, 0.5, 0.5]]])
    torch.testing.assert_close(accumulate(w, colors), torch.tensor([[0.0, 0.0, 1.0]]))


def test_uniform_medium_matches_the_closed_form():
    s, d, n = 2.0, 0.1, 6
    sigma = torch.full((1, n), s, dtype=torch.float64)
    deltas = torch.full((1, n), d, dtype=torch.float64)
    w, trans = weights_from_density(sigma, deltas)
    expected = [math.exp(-s * d * k) * (1 - math.exp(-s * d)) for k in range(n)]
    torch.testing.assert_close(w[0], torch.tensor(expected, dtype=torch.float64))
    assert math.isclose(trans.item(), math.exp(-s * d * n))
    assert math.isclose(w.sum().item() + trans.item(), 1.0)
    # a constant colour in the medium blends with the background by the transmittance
    rgb = accumulate(w, torch.full((1, n, 3), 0.2, dtype=torch.float64))
    out = composite(rgb, w.sum(-1), torch.tensor([1.0, 1.0, 1.0], dtype=torch.float64))
    torch.testing.assert_close(
        out[0], torch.full((3,), 0.2 * (1 - math.exp(-1.2)) + math.exp(-1.2), dtype=torch.float64)
    )


def test_empty_rays_render_background_and_background_class():
    sigma = torch.zeros(2, 4)
    t = torch.linspace(0.2, 1.0, 4).expand(2, 4)
    w, trans = weights_from_density(sigma, sample_deltas(t, torch.tensor([1.2, 1.2])))
    assert torch.all(w == 0) and torch.all(trans == 1)
    bg = torch.tensor([0.1, 0.2, 0.3])
    torch.testing.assert_close(composite(accumulate(w, torch.rand(2, 4, 3)), w.sum(-1), bg), bg.expand(2, 3))
    probs = torch.softmax(torch.randn(2, 4, 5), dim=-1)
    torch.testing.assert_close(render_affordance(w, probs, trans), torch.tensor([[1.0] + [0.0] * 5] * 2))
    assert torch.all(render_depth(w, t) == 0)


def test_affordance_distribution_sums_to_one_and_mixes_by_weight():
    sigma = torch.tensor([[0.5, 2.0, 1.0]])
    deltas = torch.tensor([[0.4, 0.4, 0.4]])
    w, trans = weights_from_density(sigma, deltas)
    probs = torch.tensor([[[1.0, 0.0], [0.0, 1.0], [0.5, 0.5]]])
    p = render_affordance(w, probs, trans)
    torch.testing.assert_close(p.sum(-1), torch.ones(1))
    a0 = 1 - math.exp(-0.2)
    a1 = math.exp(-0.2) * (1 - math.exp(-0.8))
    a2 = math.exp(-1.0) * (1 - math.exp(-0.4))
    torch.testing.assert_close(p[0], torch.tensor([math.exp(-1.4), a0 + 0.5 * a2, a1 + 0.5 * a2]))


def test_gradients_flow_to_densities():
    sigma = torch.tensor([[0.5, 1.0]], requires_grad=True)
    w, _ = weights_from_density(sigma, torch.ones(1, 2))
    accumulate(w, torch.tensor([[[0.0], [1.0]]])).sum().backward()
    # more density in front hides the bright sample; more at the bright sample shows it
    assert sigma.grad[0, 0] < 0 and sigma.grad[0, 1] > 0
