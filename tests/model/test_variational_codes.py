"""Variational codes (``code_kl_weight``): Gaussian codes, their KL from the prior, and the mean at inference."""

from __future__ import annotations

from dataclasses import replace

import pytest
import torch
from support import TINY_MODEL

from affnerf.errors import AffnerfError
from affnerf.model.affnerf import AffNeRF, gaussian_kl, sampled_codes, variational_codes
from affnerf.model.registry import build_model
from affnerf.model.resnet import INITIAL_LOG_VARIANCE, CodeEncoder


def test_gaussian_kl_matches_torch_distributions():
    torch.manual_seed(0)
    mean, log_var = torch.randn(5, 7), torch.randn(5, 7)
    q = torch.distributions.Normal(mean, (0.5 * log_var).exp())
    p = torch.distributions.Normal(torch.zeros(5, 7), torch.ones(5, 7))
    torch.testing.assert_close(gaussian_kl(mean, log_var), torch.distributions.kl_divergence(q, p).sum(-1))
    assert gaussian_kl(torch.zeros(2, 3), torch.zeros(2, 3)).abs().max() == 0


def test_sampled_codes_have_the_gaussians_moments_and_pass_gradients_to_both():
    torch.manual_seed(0)
    mean = torch.tensor([[1.0, -2.0, 0.0]]).expand(20000, 3).clone().requires_grad_(True)
    log_var = torch.log(torch.tensor([[0.01, 1.0, 4.0]])).expand(20000, 3).clone().requires_grad_(True)
    codes = sampled_codes(mean, log_var)
    torch.testing.assert_close(codes.mean(0), torch.tensor([1.0, -2.0, 0.0]), atol=0.05, rtol=0)
    torch.testing.assert_close(codes.std(0), torch.tensor([0.1, 1.0, 2.0]), rtol=0.03, atol=0)
    codes.square().sum().backward()
    assert mean.grad is not None and mean.grad.abs().sum() > 0
    assert log_var.grad is not None and log_var.grad.abs().sum() > 0


def test_a_diverging_log_variance_is_clamped_so_codes_stay_finite():
    codes, _, kl = variational_codes((torch.zeros(2, 3), torch.zeros(2, 3)), (torch.full((2, 3), 80.0),) * 2)
    assert torch.isfinite(codes).all() and torch.isfinite(kl).all()
    assert codes.abs().max() < 8 * (0.5 * torch.tensor(4.0)).exp()


def test_only_a_variational_encoder_has_log_variance_heads():
    plain, variational = CodeEncoder(8, 0.125), CodeEncoder(8, 0.125, second_code=True, variational=True)
    assert not any("log_var" in k for k in plain.state_dict())
    out = variational.encode_gaussian(torch.rand(2, 3, 32, 32), labels=False)
    assert out.code_log_var is not None and out.code_log_var.shape == (2, 8)
    assert out.second_log_var is not None and out.second_log_var.shape == (2, 8)
    assert plain.encode_gaussian(torch.rand(2, 3, 32, 32)).code_log_var is None


def test_training_draws_codes_and_adds_the_weighted_kl_while_evaluation_gives_the_means():
    torch.manual_seed(0)
    model = AffNeRF(replace(TINY_MODEL, code_kl_weight=0.01), num_classes=3)
    images = torch.rand(3, 3, 32, 32)
    model.eval()
    with torch.no_grad():
        means = model.encode(images)
        assert means.kl is None and model.auxiliary_losses(means) == {}
        torch.testing.assert_close(model.encode(images).shape, means.shape)
        torch.testing.assert_close(means.shape, model.shape_encoder(images))
    model.train()
    drawn = model.encode(images)
    assert drawn.kl is not None and drawn.kl.shape == (3,) and (drawn.kl > 0).all()
    assert not torch.allclose(drawn.shape, means.shape) and not torch.allclose(drawn.appearance, means.appearance)
    loss = model.auxiliary_losses(drawn)["loss/code_kl"]
    torch.testing.assert_close(loss, 0.01 * drawn.kl.mean())
    loss.backward()
    assert model.shape_encoder.log_var_head is not None and model.appearance_encoder is not None
    assert model.shape_encoder.log_var_head.weight.grad.abs().sum() > 0
    assert model.appearance_encoder.log_var_head.weight.grad.abs().sum() > 0


def test_views_of_one_object_average_their_kl():
    torch.manual_seed(0)
    model = AffNeRF(replace(TINY_MODEL, code_kl_weight=0.01, encoders="one"), num_classes=3).train()
    codes = model.encode_views(torch.rand(2, 3, 3, 32, 32), torch.zeros(2, 3, 3, 3), torch.zeros(2, 3, 4, 4))
    assert codes.kl is not None and codes.kl.shape == (2,) and (codes.kl > 0).all()


def test_a_model_without_the_weight_has_no_kl_and_no_extra_weights():
    model = AffNeRF(TINY_MODEL, num_classes=3).train()
    assert model.encode(torch.rand(2, 3, 32, 32)).kl is None
    assert not any("log_var" in k for k in model.state_dict())


def test_the_kl_weight_is_refused_for_other_models_and_below_zero():
    with pytest.raises(AffnerfError, match="--model.code-kl-weight"):
        build_model(replace(TINY_MODEL, kind="pixelnerf", code_kl_weight=0.1), 3)
    with pytest.raises(AffnerfError, match="--model.code-kl-weight"):
        build_model(replace(TINY_MODEL, code_kl_weight=-0.1), 3)


def test_variances_start_small_so_early_codes_are_not_drowned_in_noise():
    encoder = CodeEncoder(8, 0.125, variational=True)
    out = encoder.encode_gaussian(torch.rand(4, 3, 32, 32), labels=False)
    assert out.code_log_var is not None
    assert (out.code_log_var - INITIAL_LOG_VARIANCE).abs().max() < 2.0 and INITIAL_LOG_VARIANCE <= -4
