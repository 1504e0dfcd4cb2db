"""The pose-aware model: its camera vector, projection at the predicted camera, and training and prediction
without an input pose."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import torch
from support import TINY_MODEL

from affnerf.data.cameras import look_at
from affnerf.model.camera_head import (
    PARAM_PRIOR,
    camera_errors,
    camera_from_params,
    camera_loss,
    params_from_camera,
)
from affnerf.model.pixelnerf import project, sample_features
from affnerf.model.pose_aware import PoseAwareNeRF

TINY = replace(TINY_MODEL, kind="pose-aware")


def test_a_camera_on_the_x_axis_has_the_hand_computed_vector():
    c2w = torch.tensor(look_at(np.array([0.7, 0.0, 0.0]), np.zeros(3)), dtype=torch.float32)
    k = torch.tensor([96.0, 96.0, 30.0, 34.0])  # the origin lies on the optical axis: it appears at (30, 34)
    params = params_from_camera(c2w, k, 64)
    expected = torch.tensor([0.0, 1.0, 0.0, math.log(0.7), math.log(1.5), 30 / 64, 34 / 64])
    torch.testing.assert_close(params, expected, atol=1e-5, rtol=0)


def test_the_vector_rebuilds_a_camera_that_projects_like_the_true_one():
    rng = np.random.default_rng(3)
    points = torch.rand(20, 3) * 0.3 - 0.15
    for _ in range(4):
        elev, azim, dist = np.radians(rng.uniform(10, 80)), rng.uniform(0, 2 * np.pi), rng.uniform(0.5, 0.9)
        eye = dist * np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
        c2w = torch.tensor(look_at(eye, np.zeros(3)), dtype=torch.float32)
        k = torch.tensor([rng.uniform(80, 200)] * 2 + list(rng.uniform(20, 44, 2)), dtype=torch.float32)
        w2c, k2 = camera_from_params(params_from_camera(c2w, k, 64), 64)
        _, want = project(points, torch.linalg.inv(c2w), k)
        _, got = project(points, w2c, k2)
        torch.testing.assert_close(got, want, atol=1e-3, rtol=0)


def test_camera_loss_and_errors_are_zero_at_the_truth_and_measure_azimuth_in_degrees():
    true = torch.tensor([PARAM_PRIOR, PARAM_PRIOR])
    assert camera_loss(true, true).item() == pytest.approx(0.0, abs=1e-6)
    turned = true.clone()
    turned[1, 1:3] = torch.tensor([0.0, 3.0])  # 90° away, not unit length
    errors = camera_errors(turned, true)
    torch.testing.assert_close(errors["azimuth_deg"], torch.tensor([0.0, 90.0]), atol=1e-3, rtol=0)
    assert camera_loss(turned, true).item() == pytest.approx(0.5, abs=1e-5)  # (0 + 1) / 2


def test_features_are_read_bilinearly_at_crop_pixels():
    features = torch.arange(16.0).reshape(1, 4, 4).repeat(2, 1, 1)  # value = 4 * row + column
    features[1] *= -1
    # a 4-cell map over an 8-pixel crop: crop coordinate x is cell coordinate x / 2 - 0.5 (cell centres at 0.5)
    got = sample_features(features, torch.tensor([[3.0, 5.0], [2.0, 2.0]]), 8)
    # (3, 5) -> column 1, row 2 exactly; (2, 2) -> halfway between columns 0, 1 and rows 0, 1
    torch.testing.assert_close(got, torch.tensor([[4 * 2 + 1, -(4 * 2 + 1)], [2.5, -2.5]]))


def _posed_inputs(b: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    images = torch.rand(b, 1, 3, 32, 32)
    poses = torch.tensor(look_at(np.array([0.5, 0.3, 0.4]), np.zeros(3)), dtype=torch.float32).repeat(b, 1, 1, 1)
    return images, torch.tensor([[[48.0, 48.0, 16.0, 16.0]]] * b), poses


def test_projection_uses_the_predicted_camera_never_the_given_pose():
    torch.manual_seed(0)
    model = PoseAwareNeRF(TINY, 4).eval()
    images, intrinsics, poses = _posed_inputs(1)
    other = poses.clone()
    other[..., :3, 3] *= 1.5
    a, b = model.encode_views(images, intrinsics, poses), model.encode_views(images, intrinsics, other)
    alone = model.encode(images[:, 0])
    assert alone.true_camera is None and not torch.allclose(a.true_camera, b.true_camera)
    points = torch.rand(30, 3) * 0.3 - 0.15
    rays = torch.arange(30)
    obj = torch.zeros(30, dtype=torch.long)
    conds = [model.condition(e, obj)(points, rays) for e in (a, b, alone)]
    for trunk, colour in conds[1:]:
        torch.testing.assert_close(trunk, conds[0][0])
        torch.testing.assert_close(colour, conds[0][1])
    torch.testing.assert_close(a.world_to_camera, camera_from_params(a.camera.detach(), 32)[0])


def test_the_oracle_projects_with_the_given_camera_and_falls_back_to_the_predicted_one():
    torch.manual_seed(0)
    model = PoseAwareNeRF(replace(TINY, projection_camera="given"), 4).eval()
    images, intrinsics, poses = _posed_inputs(1)
    other = poses.clone()
    other[..., :3, 3] *= 1.5
    a, b = model.encode_views(images, intrinsics, poses), model.encode_views(images, intrinsics, other)
    alone = model.encode(images[:, 0])
    torch.testing.assert_close(a.world_to_camera, camera_from_params(a.true_camera, 32)[0])
    torch.testing.assert_close(alone.world_to_camera, camera_from_params(alone.camera.detach(), 32)[0])
    points = torch.rand(30, 3) * 0.3 - 0.15
    rays, obj = torch.arange(30), torch.zeros(30, dtype=torch.long)
    trunk_a, _ = model.condition(a, obj)(points, rays)
    trunk_b, _ = model.condition(b, obj)(points, rays)
    assert not torch.allclose(trunk_a, trunk_b)  # the local codes read the image where each camera projects


def test_the_camera_loss_trains_only_the_camera_head_and_the_encoder_below_it():
    torch.manual_seed(1)
    model = PoseAwareNeRF(TINY, 4)
    encoding = model.encode_views(*_posed_inputs(2))
    losses = model.auxiliary_losses(encoding)
    assert set(losses) == {"loss/camera"} and losses["loss/camera"].item() > 0
    losses["loss/camera"].backward()
    assert model.camera_head[-1].weight.grad.abs().sum() > 0
    assert model.shape_backbone.stem[0].weight.grad.abs().sum() > 0
    assert all(p.grad is None for p in model.renderer.parameters())
    assert model.auxiliary_losses(model.encode(torch.rand(1, 3, 32, 32))) == {}


def test_a_pose_aware_run_trains_logs_its_camera_loss_and_predicts_from_a_photo(tiny_train_config, tmp_path):
    from affnerf.predict.predictor import Predictor
    from affnerf.train.trainer import train

    config = tiny_train_config(model=TINY, steps=6, checkpoint_every=6)
    summary = train(config)
    assert summary.step == 6 and "loss/camera" in summary.scalars
    log = (config.out / "metrics.jsonl").read_text()
    assert '"loss/camera"' in log
    predictor = Predictor.load(config.out, device="cpu")
    crop = (np.random.default_rng(0).random((1, 32, 32, 3)) * 255).astype(np.uint8)
    codes = predictor.encode_crops(crop)
    assert codes.features.shape[:2] == (1, 1) and codes.true_camera is None
