"""Stratified and hierarchical sampling."""

from __future__ import annotations

import torch

from affnerf.rendering.samplers import merge_samples, pdf_samples, stratified_samples


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
