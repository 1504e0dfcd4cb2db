"""Triplane conditioning: plane reads, the generator, and AFF-NeRF conditioned through it."""

from __future__ import annotations

from dataclasses import replace

import pytest
import torch

from affnerf.model.affnerf import AffNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.triplane import PlaneGenerator, generator_widths, sample_planes

HALF = 0.25


def ramp_planes(resolution: int) -> torch.Tensor:
    """(3, 2, R, R) planes whose two channels hold each texel centre's two plane coordinates in metres."""
    centres = (torch.arange(resolution) + 0.5) / resolution * 2 - 1  # grid_sample's texel centres
    v, u = torch.meshgrid(centres, centres, indexing="ij")
    return torch.stack([u, v]).expand(3, 2, resolution, resolution) * HALF


def test_a_point_reads_its_own_coordinates_from_linear_ramps_in_each_plane():
    pts = torch.tensor([[0.1, -0.05, 0.2], [-0.12, 0.0, 0.03]])
    feats = sample_planes(ramp_planes(16), pts, HALF)
    assert feats.shape == (2, 6)
    expected = pts[:, [0, 1, 0, 2, 1, 2]]  # xy, xz, yz planes side by side
    torch.testing.assert_close(feats, expected, atol=1e-6, rtol=0)


def test_points_outside_the_cube_read_the_border():
    planes = ramp_planes(8)
    inside = sample_planes(planes, torch.tensor([[HALF * 0.99, 0.0, 0.0]]), HALF)
    outside = sample_planes(planes, torch.tensor([[HALF * 3, 0.0, 0.0]]), HALF)
    torch.testing.assert_close(outside, inside)


def test_the_generator_makes_three_planes_per_code_and_refuses_other_sizes():
    gen = PlaneGenerator(code_dim=8, channels=5, resolution=16, base=32)
    assert gen(torch.randn(2, 8)).shape == (2, 3, 5, 16, 16)
    assert generator_widths(16, 32) == [32, 32, 16]
    with pytest.raises(ValueError, match="power of two"):
        generator_widths(24, 32)


def tiny_triplane() -> AffNeRF:
    config = ModelConfig(
        encoder_width=0.125, encoder_resolution=32, field_width=16, field_depth=2, color_width=8,
        affordance_width=8, num_coarse=4, num_fine=0, clip_to_cube=True, conditioning="triplane",
        plane_resolution=8, plane_channels=4,
    )  # fmt: skip
    torch.manual_seed(0)
    return AffNeRF(config, num_classes=3)


def test_each_point_reads_the_planes_of_its_own_objects_code_beside_the_code():
    model = tiny_triplane()
    codes = model.encode(torch.rand(2, 3, 32, 32))
    pts = torch.rand(5, 3) * 0.2 - 0.1
    obj = torch.tensor([1, 0, 1, 1, 0])
    trunk, colour = model.condition(codes, obj)(pts, torch.arange(5))
    planes = model.planes(codes.shape)
    half = model.config.scene_half_extent
    for i in range(5):
        local = sample_planes(planes[obj[i]], pts[i : i + 1], half)[0]
        torch.testing.assert_close(trunk[i], torch.cat([local, codes.shape[obj[i]]]))
    torch.testing.assert_close(colour.per_point(), codes.appearance[obj])


def test_the_planes_are_decoded_once_per_encoding_until_the_weights_change(monkeypatch):
    model = tiny_triplane()
    calls = []
    original = model.planes.forward
    monkeypatch.setattr(model.planes, "forward", lambda c: calls.append(1) or original(c))
    codes = model.encode(torch.rand(2, 3, 32, 32))
    for _ in range(2):  # a training step: its rays, then its 3D points
        model.condition(codes, torch.tensor([0, 1]))(torch.zeros(2, 3), torch.arange(2))
    assert len(calls) == 1
    with torch.no_grad():
        model.planes.stem.weight.add_(1.0)  # as an optimiser step does
    model.condition(codes, torch.tensor([0]))(torch.zeros(1, 3), torch.arange(1))
    other = model.encode(torch.rand(2, 3, 32, 32))
    model.condition(other, torch.tensor([0]))(torch.zeros(1, 3), torch.arange(1))
    assert len(calls) == 3


def test_gradients_reach_the_generator_and_the_encoder_through_the_planes():
    model = tiny_triplane()
    codes = model.encode(torch.rand(2, 3, 32, 32))
    (field,) = model.point_geometry(codes, torch.tensor([0, 1, 1]), torch.rand(3, 3) * 0.2 - 0.1)
    density = field.density
    density.sum().backward()
    assert float(model.planes.head.weight.grad.abs().sum()) > 0
    assert float(model.shape_encoder.head.weight.grad.abs().sum()) > 0


def test_other_conditionings_build_no_generator():
    model = AffNeRF(replace(tiny_triplane().config, conditioning="concat"), num_classes=3)
    assert model.planes is None


def test_triplane_conditioning_of_a_model_without_a_shape_code_is_refused():
    from affnerf.errors import AffnerfError
    from affnerf.model.registry import build_model

    with pytest.raises(AffnerfError, match="pixelnerf model has none"):
        build_model(replace(tiny_triplane().config, kind="pixelnerf"), num_classes=3)
