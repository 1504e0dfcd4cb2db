"""GSNeRF: the plane-sweep cost volume and soft-argmin depth against hand-computed values, depth-guided samples
within their band, the source-depth loss, and a tiny end-to-end forward pass and training run."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import pytest
import torch

from affnerf.data.dataset import Dataset
from affnerf.model.config import ModelConfig
from affnerf.model.gsnerf import (
    DEPTH_BAND,
    SOURCE_DEPTH_WEIGHT,
    GeoEncoding,
    GSNeRF,
    pixel_points,
    plane_sweep_variance,
    soft_argmin,
)
from affnerf.model.inputs import dataset_views
from affnerf.model.multiview import depth_band_samples
from affnerf.model.registry import build_model

K = torch.tensor([32.0, 32.0, 16.0, 16.0])  # a 32 px crop; feature maps of 8 x 8 (4 crop px per cell)
Z0, B = 0.5, 0.05  # the textured plane's depth, the baseline of the second camera (along +x)


def _two_views_of_a_textured_plane() -> tuple[torch.Tensor, torch.Tensor]:
    """(2, 4, 4) poses of two fronto-parallel cameras B apart, and (2, 2, 8, 8) features of a plane at depth Z0
    whose texture is its world (x, y): linear, so bilinear sampling of it is exact."""
    c2w = torch.eye(4).repeat(2, 1, 1)
    c2w[:, 2, 3] = 0.6
    c2w[1, 0, 3] = B
    maps = [pixel_points(K, c2w[v], torch.tensor([Z0]), 8, 8, 32)[0, ..., :2].permute(2, 0, 1) for v in range(2)]
    return c2w, torch.stack(maps)


def test_the_cost_volume_of_a_plane_vanishes_at_its_depth_and_matches_the_hand_variance_elsewhere():
    c2w, maps = _two_views_of_a_textured_plane()
    var = plane_sweep_variance(maps, K.repeat(2, 1), c2w, 0, torch.tensor([0.4, Z0, 0.6]), 32)
    assert var.shape == (2, 3, 8, 8)
    inner = var[..., 1:]  # columns whose match in the second view lies inside its map
    assert inner[:, 1].abs().max() < 1e-10
    # at plane z, ref pixel -> world X; the second view sees there the texture x = (X - B) Z0 / z + B, the reference
    # X Z0 / z: they differ by B (1 - Z0 / z) whatever the pixel, and the variance of two values is (diff / 2)^2
    for plane, z in ((0, 0.4), (2, 0.6)):
        hand = (B * (1 - Z0 / z) / 2) ** 2
        torch.testing.assert_close(inner[0, plane], torch.full((8, 7), hand), rtol=1e-4, atol=1e-9)
        assert inner[1, plane].abs().max() < 1e-10  # no vertical parallax: y agrees at every plane


def test_soft_argmin_is_the_expected_plane_depth_under_softmax_of_minus_the_cost():
    c2w, maps = _two_views_of_a_textured_plane()
    planes = torch.tensor([0.4, Z0, 0.6])
    cost = plane_sweep_variance(maps, K.repeat(2, 1), c2w, 0, planes, 32).sum(0) * 2e4  # (3, 8, 8)
    depth, prob = soft_argmin(cost, planes)
    c = [2e4 * (B * (1 - Z0 / z) / 2) ** 2 for z in (0.4, Z0, 0.6)]  # only the x channel varies
    e = [math.exp(-x) for x in c]
    hand = sum(w * z for w, z in zip(e, (0.4, Z0, 0.6), strict=True)) / sum(e)
    assert depth[4, 4].item() == pytest.approx(hand, rel=1e-5)
    assert prob[:, 4, 4].sum().item() == pytest.approx(1.0)
    flat, _ = soft_argmin(torch.zeros(3, 1, 1), planes)
    assert flat.item() == pytest.approx(0.5)  # equal costs: the mean plane


def test_depth_guided_samples_lie_in_the_band_around_the_predicted_depth():
    t_star = torch.tensor([0.5, 0.31, 1.0])
    near, far = torch.tensor([0.3, 0.3, 0.3]), torch.tensor([0.9, 0.9, 0.9])
    t = depth_band_samples(t_star, near, far, 0.03, 16, perturb=True, generator=torch.Generator().manual_seed(0))
    assert t.shape == (3, 16)
    assert ((t[0] >= 0.47) & (t[0] <= 0.53)).all()
    assert ((t[1] >= 0.3) & (t[1] <= 0.34)).all()  # clipped at near
    assert torch.all(t[2] == 0.9)  # a predicted depth beyond the ray's end: every sample at the end


def _one_view_encoding(depth: float) -> GeoEncoding:
    """One camera at z = 0.7 looking down -z whose predicted depth is ``depth`` everywhere."""
    c2w = torch.eye(4)
    c2w[2, 3] = 0.7
    return GeoEncoding(
        features=torch.rand(1, 1, 4, 8, 8),
        images=torch.rand(1, 1, 3, 32, 32),
        intrinsics=K[None, None],
        world_to_camera=torch.linalg.inv(c2w)[None, None],
        size=32,
        semantic=torch.rand(1, 1, 2, 8, 8),
        depth=torch.full((1, 1, 8, 8), depth),
    )


def test_the_fine_samples_go_around_the_depth_the_source_view_predicts():
    model = build_model(ModelConfig(kind="gsnerf", encoder_width=0.125, field_width=16, num_fine=8, code_dim=8), 5)
    encoding = _one_view_encoding(0.6)  # the surface is at world z = 0.1
    origins, dirs = torch.tensor([[0.0, 0.0, 0.8]]), torch.tensor([[0.0, 0.0, -1.0]])
    t = torch.tensor([[0.5, 0.6, 0.7, 0.8, 0.9]])  # world z 0.3 ... -0.1: depth 0.6 in the view at t = 0.7
    points = origins[:, None] + t[..., None] * dirs[:, None]
    assert model.ray_depth(encoding, 0, points, t).item() == pytest.approx(0.7)
    sampler = model.fine_sampler(encoding, torch.zeros(1, dtype=torch.long))
    near, far = torch.tensor([0.5]), torch.tensor([0.9])
    fine = sampler(origins, dirs, torch.zeros(1, dtype=torch.long), t, near, far, True, None)
    assert fine.shape == (1, 8) and ((fine >= 0.7 - DEPTH_BAND) & (fine <= 0.7 + DEPTH_BAND)).all()


def test_the_source_depth_loss_is_the_l1_over_pixels_with_a_surface():
    encoding = _one_view_encoding(0.6)
    truth = torch.zeros(1, 1, 32, 32)
    truth[..., :16, :] = 0.5  # top half: a surface 0.1 m nearer than predicted; bottom half: none
    assert GSNeRF.source_depth_loss(encoding, truth).item() == pytest.approx(0.1)


def test_training_adds_the_weighted_source_depth_loss_when_the_batch_has_depth():
    encoding = _one_view_encoding(0.6)
    truth = torch.full((1, 1, 32, 32), 0.4)
    model = object.__new__(GSNeRF)  # the loss reads only the encoding
    losses = GSNeRF.auxiliary_losses(model, encoding, truth)
    assert losses["loss/source_depth"].item() == pytest.approx(SOURCE_DEPTH_WEIGHT * 0.2)
    assert GSNeRF.auxiliary_losses(model, encoding, None) == {}


def test_gsnerf_renders_the_tiny_dataset_and_trains_five_steps(train_dataset, tiny_train_config):
    from affnerf.train.trainer import train

    config = tiny_train_config(steps=5, checkpoint_every=5, input_views=2)
    config = replace(config, model=replace(config.model, kind="gsnerf"))
    torch.manual_seed(0)
    model = build_model(config.model, 12)
    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects("train")[0])
    images, intr, poses = dataset_views(obj, [0, 1], config.model)
    encoding = model.encode_views(images, intr, poses)
    assert encoding.depth.shape == (1, 2, 8, 8) and torch.isfinite(encoding.depth).all()
    origins = torch.as_tensor(obj.pose(2), dtype=torch.float32)[:3, 3].repeat(5, 1)  # a third view's camera
    dirs = -origins / origins.norm(dim=-1, keepdim=True) + torch.randn(5, 3) * 0.05
    coarse, fine = model.render_rays(encoding, torch.zeros(5, dtype=torch.long), origins, dirs, torch.ones(5, 3))
    assert fine is not None and fine.affordance.shape == (5, 12) and torch.isfinite(fine.rgb).all()
    summary = train(config)
    assert summary.step == 5 and (config.out / "checkpoints" / "step_00000005.pt").exists()
    rows = [json.loads(line) for line in (config.out / "metrics.jsonl").read_text().splitlines()]
    assert all(r["loss/source_depth"] > 0 for r in rows)  # the Geo-Reasoner's depth is supervised in training
