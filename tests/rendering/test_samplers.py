"""Stratified and hierarchical sampling."""

from __future__ import annotations

import torch

from affnerf.rendering.samplers import (
    SurfaceGuide,
    guided_samples,
    merge_samples,
    pdf_samples,
    stratified_samples,
    surface_samples,
)


def test_stratified_samples_one_per_bin():
    near, far = torch.tensor([0.1, 0.5]), torch.tensor([1.5, 0.9])
    g = torch.Generator().manual_seed(0)
    t = stratified_samples(near, far, 8, perturb=True, generator=g)
    bins = (t - near[:, None]) / (far - near)[:, None] * 8
    torch.testing.assert_close(torch.floor(bins), torch.arange(8.0).expand(2, 8))
    centres = stratified_samples(near, far, 8, perturb=False)
    torch.testing.assert_close(centres[0, 0], torch.tensor(0.1 + 1.4 / 16))


def test_pdf_samples_concentrate_in_the_heavy_bin():
    t = torch.linspace(0.05, 0.95, 10).expand(3, 10)  # bins of width 0.1 centred on t
    weights = torch.zeros(3, 10)
    weights[:, 6] = 1.0
    s = pdf_samples(t, weights, 64, perturb=True, generator=torch.Generator().manual_seed(1), eps=0.0)
    assert torch.all(s >= 0.6 - 1e-6) and torch.all(s <= 0.7 + 1e-6)
    assert torch.all(s[:, 1:] >= s[:, :-1])


def test_pdf_samples_of_uniform_weights_are_quantiles():
    t = torch.linspace(0.05, 0.95, 10)[None]
    s = pdf_samples(t, torch.ones(1, 10), 5, perturb=False)
    torch.testing.assert_close(s, torch.tensor([[0.1, 0.3, 0.5, 0.7, 0.9]]))


def test_pdf_samples_of_an_empty_ray_are_uniform():
    t = torch.linspace(0.05, 0.95, 10)[None]
    s = pdf_samples(t, torch.zeros(1, 10), 4, perturb=False)
    torch.testing.assert_close(s, torch.tensor([[0.125, 0.375, 0.625, 0.875]]))


def test_merge_sorts_the_union():
    torch.testing.assert_close(
        merge_samples(torch.tensor([[0.1, 0.5]]), torch.tensor([[0.3]])), torch.tensor([[0.1, 0.3, 0.5]])
    )


def test_surface_samples_gather_around_the_depth_inside_the_interval():
    g = torch.Generator().manual_seed(0)
    depth, near, far = torch.tensor([0.6, 0.95]), torch.tensor([0.2, 0.2]), torch.tensor([1.0, 1.0])
    t = surface_samples(depth, near, far, 4000, 0.02, g)
    assert t.shape == (2, 4000) and bool((t[:, 1:] >= t[:, :-1]).all())
    assert bool((t >= 0.2).all() and (t <= 1.0).all())
    assert abs(t[0].mean().item() - 0.6) < 0.002 and abs(t[0].std().item() - 0.02) < 0.002
    assert (t[1] == 1.0).float().mean().item() > 0.9 * 0.0062  # draws past the interval's end are kept at it
    assert bool((t[1] <= 1.0).all())


def test_guided_samples_move_only_the_share_of_surface_rays():
    g = torch.Generator().manual_seed(1)
    t = torch.sort(torch.rand(3, 10, generator=g) * 0.4, dim=-1).values
    guide = SurfaceGuide(torch.tensor([0.8, 0.0, 0.9]), share=0.3, sigma=0.0)
    out = guided_samples(t, guide, torch.zeros(3), torch.ones(3), g)
    assert bool((out[:, 1:] >= out[:, :-1]).all())
    assert torch.equal(out[1], t[1])  # a ray that meets no surface keeps its samples
    assert (out[0] == 0.8).sum() == 3 and (out[2] == 0.9).sum() == 3
    assert torch.equal(out[0, :7], t[0, 3:])  # the first three of the drawn samples gave way
    none = guided_samples(t, SurfaceGuide(guide.depth, share=0.0, sigma=0.01), torch.zeros(3), torch.ones(3), g)
    assert torch.equal(none, t)
