"""Semantic-Ray: projection into posed views, Cross-Reprojection Attention against hand-computed values, and a
tiny end-to-end forward pass and training run."""

from __future__ import annotations

import math
from dataclasses import replace

import torch
from support import train_argv
from torch.nn import functional as F

from affnerf.cli.main import main
from affnerf.data.dataset import Dataset
from affnerf.model.inputs import dataset_views
from affnerf.model.multiview import attend, sample_views
from affnerf.model.registry import build_model
from affnerf.model.semantic_ray import CrossReprojectionAttention, SemanticRay

K = torch.tensor([40.0, 40.0, 16.0, 16.0])  # fl_x, fl_y, cx, cy of a 32 px crop


def _pixel_coordinate_maps(size: int = 32, h: int = 8) -> torch.Tensor:
    """(2, h, h) map whose value at each pixel centre is that centre's crop coordinate (u, v): linear, so a
    bilinear read anywhere inside returns the position read."""
    centres = (torch.arange(h, dtype=torch.float32) + 0.5) * size / h
    return torch.stack([centres[None, :].expand(h, h), centres[:, None].expand(h, h)])


def test_a_point_projected_into_two_views_samples_the_expected_feature():
    front = torch.eye(4)
    front[2, 3] = 0.7  # at +z, looking down -z
    side = torch.tensor([[0.0, 0, 1, 0.7], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]])  # at +x, looking along -x
    w2c = torch.linalg.inv(torch.stack([front, side]))
    maps = _pixel_coordinate_maps()[None].repeat(2, 1, 1, 1)
    point = torch.tensor([[0.05, -0.02, 0.1], [-1.5, 0.0, 0.75]])  # the second is behind the front camera
    values, cams, valid = sample_views(point, maps, w2c, K.repeat(2, 1), 32)
    # front: camera frame (0.05, -0.02, -0.6); side: x_cam = y, y_cam = z, z_cam = x - 0.7 -> (-0.02, 0.1, -0.65)
    expected_front = [40 * 0.05 / 0.6 + 16, -40 * -0.02 / 0.6 + 16]
    expected_side = [40 * -0.02 / 0.65 + 16, -40 * 0.1 / 0.65 + 16]
    torch.testing.assert_close(values[0], torch.tensor([expected_front, expected_side]))
    torch.testing.assert_close(cams[0, 1], torch.tensor([-0.02, 0.1, -0.65]))
    assert valid[0].tolist() == [True, True] and valid[1].tolist() == [False, True]


def _identity(layer: torch.nn.Linear) -> None:
    with torch.no_grad():
        layer.weight.copy_(torch.eye(layer.weight.shape[0]))
        layer.bias.zero_()


def test_cross_view_attention_is_the_softmax_weighted_sum_of_the_views():
    cra = CrossReprojectionAttention(2)
    for layer in (cra.view_q, cra.view_k, cra.view_v):
        _identity(layer)
    tokens = torch.tensor([[1.0, 0.0], [0.0, 2.0], [3.0, 1.0]])[None, None]  # (R=1, S=1, V=3, D=2)
    valid = torch.tensor([[[True, True, False]]])  # the third view does not see the sample
    out, weights = cra.across_views(tokens, valid)
    q = [0.5, 1.0]  # mean of the two valid views
    scores = [(q[0] * t[0] + q[1] * t[1]) / math.sqrt(2) for t in ([1.0, 0.0], [0.0, 2.0])]
    w = [math.exp(s) / sum(math.exp(x) for x in scores) for s in scores]
    attended = [w[0] * 1.0 + w[1] * 0.0, w[0] * 0.0 + w[1] * 2.0]
    hand = F.layer_norm(torch.tensor([q[0] + attended[0], q[1] + attended[1]]), (2,))
    torch.testing.assert_close(weights[0, 0], torch.tensor([w[0], w[1], 0.0]))
    torch.testing.assert_close(out[0, 0], hand)


def test_attention_along_the_ray_mixes_a_views_samples_and_a_one_sample_ray_keeps_its_own():
    q = torch.tensor([[1.0, 0.0]])
    k = torch.tensor([[1.0, 0.0], [0.0, 1.0], [2.0, 0.0]])
    v = torch.tensor([[1.0], [2.0], [4.0]])
    out, w = attend(q, k, v, torch.tensor([True, True, False]))
    e = [math.exp(1 / math.sqrt(2)), 1.0]
    assert math.isclose(out.item(), (e[0] * 1 + e[1] * 2) / sum(e), rel_tol=1e-6) and w[0, 2] == 0
    out, _ = attend(q, k, v, torch.zeros(3, dtype=torch.bool))  # no key allowed: all are used
    assert out.item() > 2.0
    torch.manual_seed(0)
    cra = CrossReprojectionAttention(4)
    x = torch.randn(3, 1, 2, 4)  # one-sample rays: the along-ray attention returns each token's own value
    _, _, value = cra.ray_qkv(x).chunk(3, dim=-1)
    expected = cra.norm_ray(x + cra.ray_out(value))
    torch.testing.assert_close(cra.along_ray(x, torch.ones(3, 1, 2, dtype=torch.bool)), expected)


def test_semantic_ray_renders_the_tiny_dataset_and_trains_five_steps(train_dataset, tiny_train_config):
    config = tiny_train_config(steps=5, checkpoint_every=5, input_views=2)
    config = replace(config, model=replace(config.model, kind="semantic-ray"))
    torch.manual_seed(0)
    model = build_model(config.model, 12)
    assert isinstance(model, SemanticRay)
    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects("train")[0])
    images, intr, poses = dataset_views(obj, [0, 1], config.model)
    encoding = model.encode_views(images, intr, poses)
    origins = torch.as_tensor(obj.pose(2), dtype=torch.float32)[:3, 3].repeat(5, 1)  # a third view's camera
    dirs = -origins / origins.norm(dim=-1, keepdim=True) + torch.randn(5, 3) * 0.05
    coarse, fine = model.render_rays(encoding, torch.zeros(5, dtype=torch.long), origins, dirs, torch.ones(5, 3))
    assert fine is not None and fine.affordance.shape == (5, 12) and torch.isfinite(fine.rgb).all()
    argv = train_argv(config, "--input-views", "2")
    assert "--model.kind" in argv and argv[argv.index("--model.kind") + 1] == "semantic-ray"
    assert main(argv) == 0  # affnerf train --model.kind semantic-ray --input-views 2 ...
    assert (config.out / "checkpoints" / "step_00000005.pt").exists()


def test_the_fast_path_skips_empty_rays_and_renders_the_others_as_in_training():
    from affnerf.model.config import ModelConfig
    from affnerf.rendering.grid import OccupancyGrid

    torch.manual_seed(0)
    config = ModelConfig(kind="semantic-ray", encoder_width=0.125, field_width=16, code_dim=8, clip_to_cube=True)
    model = build_model(replace(config, num_coarse=8, num_fine=8), 5).eval()
    pose = torch.eye(4)
    pose[2, 3] = 0.7
    encoding = model.encode_views(torch.rand(1, 2, 3, 32, 32), K.repeat(1, 2, 1), pose.repeat(1, 2, 1, 1))
    origins, dirs = torch.tensor([[0.05, 0.05, 0.8], [-0.1, -0.1, 0.8]]), torch.tensor([[0.0, 0.0, -1.0]] * 2)
    occupied = torch.zeros(4, 4, 4, dtype=torch.bool)
    occupied[2, 2, :] = True  # the column [0, 0.125]^2 the first ray runs down; the second ray misses it
    with torch.no_grad():
        fast = model.render_rays_in_grid(encoding, OccupancyGrid(occupied, 0.25), origins, dirs, torch.ones(2, 3))
        _, fine = model.render_rays(encoding, torch.zeros(1, dtype=torch.long), origins[:1], dirs[:1], torch.ones(1, 3))
    torch.testing.assert_close(fast.rgb[0], fine.rgb[0])
    torch.testing.assert_close(fast.affordance[0], fine.affordance[0])
    assert fast.opacity[1] == 0 and torch.all(fast.rgb[1] == 1)
