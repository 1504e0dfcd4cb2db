"""The conditional field's density parameterisations: a softplus of the head (the paper) or VolSDF's density of a
signed distance."""

from __future__ import annotations

import torch

from affnerf.model.field import SDF_BETA_INIT, SDF_BETA_MIN, SDF_START, ConditionalField, laplace_density


def _field(sdf: bool) -> ConditionalField:
    torch.manual_seed(0)
    return ConditionalField(num_classes=4, code_dim=8, width=32, depth=4, sdf=sdf)


def test_laplace_density_is_half_its_inside_value_on_the_surface_and_falls_monotonically_outwards():
    d = torch.linspace(-0.1, 0.1, 201)
    sigma = laplace_density(d, 0.01)
    assert torch.all(sigma[1:] <= sigma[:-1])  # non-increasing in the distance
    assert abs(float(sigma[100]) - 50.0) < 1e-4 and abs(float(sigma[0]) - 100.0) < 1e-2
    assert float(sigma[-1]) < 1e-2  # 10 cm outside: empty


def test_a_fresh_signed_distance_field_starts_everywhere_outside_and_nearly_empty():
    field = _field(sdf=True)
    points, code = torch.rand(64, 3) - 0.5, torch.randn(64, 8)
    out = field.supervised(points, code)
    torch.testing.assert_close(out.distance, torch.full((64,), SDF_START))
    expected = laplace_density(torch.tensor(SDF_START), SDF_BETA_INIT)
    torch.testing.assert_close(out.density, expected.expand(64))
    assert float(expected) < 0.15 * 0.5 / SDF_BETA_INIT  # under 15 % of the surface's density
    torch.testing.assert_close(field.density_only(points, code), out.density)
    assert _field(sdf=False).supervised(points, code).distance is None


def test_the_distance_and_beta_learn_and_beta_stops_at_its_floor():
    field = _field(sdf=True)
    points, code = torch.rand(32, 3) - 0.5, torch.randn(32, 8)
    out = field.supervised(points, code)
    (out.distance.sum() + out.density.sum()).backward()
    assert float(field.density.weight.grad.abs().sum()) > 0 and field.log_beta.grad is not None
    with torch.no_grad():
        field.log_beta.fill_(-20.0)
    assert abs(float(field.beta().detach()) - SDF_BETA_MIN) < 1e-9
