"""Encoders, positional encoding and the conditional field."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
import torch

from affnerf.errors import AffnerfError
from affnerf.model.affnerf import AffNeRF, noisy_codes
from affnerf.model.config import ModelConfig
from affnerf.model.encoding import encoding_dim, positional_encoding
from affnerf.model.field import ConditionalField, ObjectCodes
from affnerf.model.registry import build_model
from affnerf.model.resnet import CodeEncoder, ResNet18, spatial_soft_argmax
from affnerf.rendering.samplers import SurfaceGuide

SMALL = ModelConfig(
    encoder_width=0.125,
    encoder_resolution=32,
    field_width=32,
    field_depth=4,
    num_coarse=8,
    num_fine=8,
    clip_to_cube=True,
    color_width=16,
    affordance_width=16,
)


def test_resnet18_has_the_standard_layout():
    net = ResNet18(1.0)
    assert net.channels == [64, 128, 256, 512]
    params = sum(p.numel() for p in net.parameters())
    assert 11.0e6 < params < 11.3e6  # ResNet18 without its classifier: 11.18 M
    feats = net(torch.rand(1, 3, 64, 64))
    assert [f.shape[1:] for f in feats] == [(64, 16, 16), (128, 8, 8), (256, 4, 4), (512, 2, 2)]


def test_an_image_encodes_the_same_alone_or_in_a_batch():
    torch.manual_seed(0)
    enc = CodeEncoder(32, 0.25).eval()
    images = torch.rand(4, 3, 48, 48)
    together = enc(images)
    alone = torch.cat([enc(images[i : i + 1]) for i in range(4)])
    torch.testing.assert_close(together, alone, atol=1e-5, rtol=1e-5)
    assert together.shape == (4, 32)


def test_positional_encoding_layout():
    x = torch.tensor([[0.25, -0.5, 1.0]])
    enc = positional_encoding(x, 3)
    assert enc.shape == (1, encoding_dim(3, 3)) == (1, 21)
    torch.testing.assert_close(enc[0, :3], x[0])
    # frequency 2 (2^2 pi), sine of the first coordinate
    assert math.isclose(enc[0, 3 + 2 * 6].item(), math.sin(4 * math.pi * 0.25), abs_tol=1e-6)


def test_affordance_and_density_ignore_the_view_direction_and_appearance_code():
    torch.manual_seed(0)
    field = ConditionalField(num_classes=5, code_dim=8, width=32, depth=4, color_width=16, affordance_width=16)
    pts = torch.rand(10, 3) - 0.5
    shape = torch.randn(10, 8)
    a = field(pts, torch.nn.functional.normalize(torch.randn(10, 3), dim=-1), shape, torch.randn(10, 8))
    b = field(pts, torch.nn.functional.normalize(torch.randn(10, 3), dim=-1), shape, torch.randn(10, 8))
    torch.testing.assert_close(a.logits, b.logits)
    torch.testing.assert_close(a.sigma, b.sigma)
    assert not torch.allclose(a.rgb, b.rgb)
    assert a.logits.shape == (10, 4)  # object classes only; background comes from transmittance
    assert torch.all(a.sigma >= 0) and torch.all((a.rgb >= 0) & (a.rgb <= 1))
    sigma, logits = field.geometry(pts, shape)
    torch.testing.assert_close(sigma, a.sigma)
    torch.testing.assert_close(logits, a.logits)


def test_the_shape_code_changes_the_geometry():
    torch.manual_seed(1)
    field = ConditionalField(num_classes=3, code_dim=8, width=32, depth=2)
    pts = torch.rand(50, 3) - 0.5
    assert not torch.allclose(field.density_only(pts, torch.zeros(50, 8)), field.density_only(pts, torch.ones(50, 8)))


def test_rays_missing_the_cube_render_background_without_evaluation():
    torch.manual_seed(0)
    model = AffNeRF(SMALL, num_classes=4)
    codes = model.encode(torch.rand(1, 3, 32, 32))
    origins = torch.tensor([[0.0, 0.0, 0.8], [0.0, 0.8, 0.8]])
    dirs = torch.tensor([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])  # the second passes beside the cube
    bg = torch.tensor([[0.2, 0.3, 0.4]] * 2)
    coarse, fine = model.render_rays(codes, torch.zeros(2, dtype=torch.long), origins, dirs, bg)
    torch.testing.assert_close(fine.rgb[1], bg[1])
    assert fine.opacity[1] == 0 and fine.affordance[1, 0] == 1
    torch.testing.assert_close(fine.affordance.sum(-1), torch.ones(2))
    assert fine.t.shape == (2, 16) and coarse.t.shape == (2, 8)
    assert torch.all(fine.t[0] >= 0.55 - 1e-6) and torch.all(fine.t[0] <= 1.05 + 1e-6)  # inside the cube


def test_a_batch_where_no_ray_meets_the_cube_renders_background():
    model = AffNeRF(SMALL, num_classes=4)
    codes = model.encode(torch.rand(1, 3, 32, 32))
    origins = torch.tensor([[0.0, 0.8, 0.8]] * 3)
    dirs = torch.tensor([[0.0, 0.0, -1.0]] * 3)
    coarse, fine = model.render_rays(codes, torch.zeros(3, dtype=torch.long), origins, dirs, torch.ones(3, 3))
    assert torch.all(fine.rgb == 1) and torch.all(fine.opacity == 0) and torch.all(fine.affordance[:, 0] == 1)


def test_every_config_kind_has_a_registered_model():
    from affnerf.model.registry import MODEL_KINDS, build_model, config_kinds

    assert set(config_kinds()) == set(MODEL_KINDS)
    for kind in config_kinds():
        assert type(build_model(replace(SMALL, kind=kind), 5)) is MODEL_KINDS[kind]
    with pytest.raises(ValueError, match="unknown model kind 'nerfacto'"):
        build_model(replace(SMALL, kind="nerfacto"), 5)  # type: ignore[arg-type]


@pytest.mark.parametrize("kind", ["affnerf", "pixelnerf", "semantic-ray", "gsnerf", "pose-aware"])
def test_point_geometry_of_several_objects_matches_each_objects_own_field(kind):
    from affnerf.model.registry import build_model

    torch.manual_seed(0)
    model = build_model(replace(SMALL, kind=kind), 5).eval()
    poses = torch.eye(4).repeat(2, 1, 1, 1)
    poses[..., 2, 3] = 0.7
    encoding = model.encode_views(torch.rand(2, 1, 3, 32, 32), torch.tensor([[[40.0, 40.0, 16.0, 16.0]]] * 2), poses)
    points = torch.rand(12, 3) * 0.4 - 0.2
    which = torch.tensor([0, 1] * 6)
    fields = model.point_geometry(encoding, which, points)
    assert len(fields) == 2 and fields[0][0].shape == (12,) and fields[1][1].shape == (12, 4)
    for index in (0, 1):
        density, labels = model.point_fields(encoding, index)
        mine = which == index
        torch.testing.assert_close(fields[-1][0][mine], density(points[mine]))
        assert torch.equal(fields[-1][1][mine].argmax(-1) + 1, labels(points[mine]))
    assert not torch.allclose(fields[0][0], fields[1][0])  # the coarse field, then the fine one


def test_a_fresh_film_field_equals_the_concatenating_one_and_film_lets_the_code_scale_every_layer():
    torch.manual_seed(2)
    plain = ConditionalField(num_classes=3, code_dim=8, width=32, depth=4)
    film = ConditionalField(num_classes=3, code_dim=8, width=32, depth=4, film=True)
    film.load_state_dict(plain.state_dict(), strict=False)  # same trunk and heads; the modulation starts at zero
    pts, code = torch.rand(20, 3) - 0.5, torch.randn(20, 8)
    torch.testing.assert_close(film.density_only(pts, code), plain.density_only(pts, code))
    with torch.no_grad():
        film.film.bias[:32] = 1.0  # gamma of the first layer: its pre-activation doubles
    assert not torch.allclose(film.density_only(pts, code), plain.density_only(pts, code))
    assert film.film.out_features == 2 * 32 * 4


@pytest.mark.parametrize("film", [False, True])
def test_factored_object_codes_give_the_field_and_its_gradients_that_per_point_codes_give(film):
    torch.manual_seed(3)
    field = ConditionalField(num_classes=4, code_dim=16, width=32, depth=4, film=film)
    if film:
        torch.nn.init.normal_(field.film.weight, std=0.1)
    shape, appearance = torch.randn(3, 16, requires_grad=True), torch.randn(3, 16, requires_grad=True)
    pick = torch.nn.functional.one_hot(torch.tensor([0, 2, 2, 1, 0, 1, 2]), 3).float()
    pts, dirs = torch.rand(7, 3) - 0.5, torch.nn.functional.normalize(torch.randn(7, 3), dim=-1)

    def outputs(s, a):
        out = field(pts, dirs, s, a)
        return torch.cat([out.sigma[:, None], out.rgb, out.logits], dim=-1)

    factored = outputs(ObjectCodes(shape, pick), ObjectCodes(appearance, pick))
    per_point = outputs(pick @ shape, pick @ appearance)
    torch.testing.assert_close(factored, per_point)
    grads = [
        torch.autograd.grad(o.square().sum(), [shape, appearance, field.trunk_layers[0].weight])
        for o in (factored, per_point)
    ]
    for g_factored, g_point in zip(*grads, strict=True):
        torch.testing.assert_close(g_factored, g_point)


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU (CI machines have none)")
@pytest.mark.parametrize("kind", ["affnerf", "pixelnerf"])
def test_point_fields_of_a_model_on_a_gpu_take_points_from_the_cpu_as_mesh_extraction_makes_them(kind):
    from affnerf.model.registry import build_model
    from affnerf.predict.mesh import evaluate_grid
    from affnerf.rendering.grid import build_grid

    torch.manual_seed(0)
    model = build_model(replace(SMALL, kind=kind), 5).eval().cuda()
    poses = torch.eye(4).repeat(1, 1, 1, 1)
    poses[..., 2, 3] = 0.7
    encoding = model.encode_views(
        torch.rand(1, 1, 3, 32, 32).cuda(), torch.tensor([[[40.0, 40.0, 16.0, 16.0]]]).cuda(), poses.cuda()
    )
    density, labels = model.point_fields(encoding, 0)
    grid = build_grid(density, 0.22, resolution=8, threshold=-1.0, device="cuda")  # every cell occupied
    volume = evaluate_grid(density, 6, 0.22, occupancy=grid)
    points = torch.rand(10, 3) * 0.4 - 0.2
    assert volume.shape == (6, 6, 6) and labels(points).device.type == "cuda"


def test_a_shared_coarse_field_places_the_fine_samples_with_the_one_field_and_without_gradients():
    torch.manual_seed(0)
    own = AffNeRF(SMALL, num_classes=4)
    shared = AffNeRF(replace(SMALL, coarse_field="shared"), num_classes=4)
    assert shared.fine is None and not any(k.startswith("renderer.fine.") for k in shared.state_dict())
    assert sum(p.numel() for p in shared.parameters()) < sum(p.numel() for p in own.parameters())
    codes = shared.encode(torch.rand(2, 3, 32, 32))
    origins = torch.tensor([[0.0, 0.0, 0.8], [0.05, 0.0, 0.8], [0.0, 0.8, 0.8]])
    dirs = torch.tensor([[0.0, 0.0, -1.0]] * 3)  # the third passes beside the cube
    bg = torch.full((3, 3), 0.5)
    generator = torch.Generator().manual_seed(0)
    coarse, fine = shared.render_rays(codes, torch.tensor([0, 1, 0]), origins, dirs, bg, True, generator)
    assert not coarse.rgb.requires_grad and fine.rgb.requires_grad and fine.t.shape == (3, 16)
    fine.rgb.sum().backward()
    assert shared.coarse.trunk_layers[0].weight.grad.abs().sum() > 0  # the one field learns from the fine pass
    # the coarse pass is the fine field's own rendering at the stratified samples
    with torch.no_grad():
        again, _ = shared.render_rays(codes, torch.tensor([0, 1, 0]), origins, dirs, bg)
        far = shared.renderer.ray_bounds(origins[:2], dirs[:2])[1]
        condition = shared.condition(codes, torch.tensor([0, 1]))
        alone = shared.renderer._stage(
            shared.coarse, again.t[:2], far, origins[:2], dirs[:2], torch.tensor([0, 1]), condition, bg[:2]
        )
    torch.testing.assert_close(again.rgb[:2], alone.rgb)
    assert len(shared.point_geometry(codes, torch.tensor([0, 1]), torch.rand(2, 3) - 0.5)) == 1


def test_one_encoder_gives_both_codes_from_one_trunk_and_both_heads_learn():
    torch.manual_seed(0)
    one = AffNeRF(replace(SMALL, encoders="one"), num_classes=3)
    two = AffNeRF(SMALL, num_classes=3)
    assert one.appearance_encoder is None and one.shape_encoder.second_head is not None
    assert two.shape_encoder.second_head is None
    trunk = sum(p.numel() for p in one.shape_encoder.backbone.parameters())
    saved = sum(p.numel() for p in two.parameters()) - sum(p.numel() for p in one.parameters())
    assert saved == trunk  # the second trunk goes, its linear layer stays as the second head
    codes = one.encode(torch.rand(2, 3, 32, 32))
    assert codes.shape.shape == codes.appearance.shape == (2, 32)
    assert not torch.allclose(codes.shape, codes.appearance)
    (codes.shape.sum() + codes.appearance.sum()).backward()
    assert one.shape_encoder.head.weight.grad.abs().sum() > 0
    assert one.shape_encoder.second_head.weight.grad.abs().sum() > 0


def test_keypoints_give_where_each_channel_peaks():
    features = torch.full((1, 2, 8, 8), -20.0)
    features[0, 0, 1, 6] = 20.0  # channel 0 peaks near the top right, channel 1 is flat
    points = spatial_soft_argmax(features)
    assert points.shape == (1, 4)
    torch.testing.assert_close(points[0, :2], torch.tensor([0.625, -0.625]), atol=1e-4, rtol=0)
    torch.testing.assert_close(points[0, 2:], torch.zeros(2), atol=1e-6, rtol=0)


def test_a_keypoint_shape_encoder_codes_where_a_shape_is_which_the_mean_cannot():
    torch.manual_seed(0)
    model = AffNeRF(replace(SMALL, shape_pooling="keypoints"), num_classes=3)
    encoder = model.shape_encoder
    assert encoder.pooling == "keypoints" and model.appearance_encoder.pooling == "mean"
    channels = encoder.backbone.channels
    assert encoder.head.in_features == channels[3] + 2 * (channels[1] + channels[2])
    left, right = torch.ones(1, 3, 32, 32), torch.ones(1, 3, 32, 32)
    left[..., 8:24, 2:10], right[..., 8:24, 22:30] = 0.0, 0.0  # one dark block, mirrored
    pooled = [encoder.pool(encoder.backbone(image)) for image in (left, right)]
    # its keypoints' x coordinates move with the block; the mean of the last stage barely sees the difference
    keypoint_x = [p[0, channels[3] :: 2] for p in pooled]
    assert (keypoint_x[1] - keypoint_x[0]).mean() > 0.05
    codes = model.encode(torch.rand(2, 3, 32, 32))
    codes.shape.sum().backward()
    assert encoder.backbone.layers[1][0].conv1.weight.grad.abs().sum() > 0


def test_only_aff_nerf_pools_its_shape_encoder_into_keypoints():
    with pytest.raises(AffnerfError, match="shape-pooling pools AFF-NeRF's shape encoder"):
        build_model(replace(SMALL, kind="pixelnerf", shape_pooling="keypoints"), 3)
    with pytest.raises(ValueError, match="pooling is mean or keypoints"):
        CodeEncoder(32, 0.25, pooling="max")


def test_only_aff_nerf_merges_its_encoders():
    with pytest.raises(AffnerfError, match="merges AFF-NeRF's two encoders"):
        build_model(replace(SMALL, kind="pixelnerf", encoders="one"), 3)


def test_code_noise_perturbs_training_codes_in_proportion_to_their_spread_and_never_inference_codes():
    torch.manual_seed(0)
    codes = torch.randn(4096, 3) * torch.tensor([0.1, 1.0, 10.0])
    noise = noisy_codes(codes, 0.2) - codes
    torch.testing.assert_close(noise.std(dim=0), 0.2 * codes.std(dim=0), rtol=0.05, atol=0)
    assert noise.mean(dim=0).abs().max() < 0.02 * 10
    assert torch.equal(noisy_codes(codes[:1], 0.2), codes[:1])
    model = AffNeRF(replace(SMALL, code_noise=0.5), num_classes=3)
    images = torch.rand(3, 3, 32, 32)
    model.eval()
    with torch.no_grad():
        a, b = model.encode(images), model.encode(images)
    torch.testing.assert_close(a.shape, b.shape)
    model.train()
    noisy = model.encode(images)
    assert not torch.allclose(noisy.shape, a.shape) and not torch.allclose(noisy.appearance, a.appearance)


def test_code_noise_is_refused_for_other_models_and_below_zero():
    with pytest.raises(AffnerfError, match="--model.code-noise"):
        build_model(replace(SMALL, kind="pixelnerf", code_noise=0.1), 3)
    with pytest.raises(AffnerfError, match="--model.code-noise"):
        build_model(replace(SMALL, code_noise=-0.1), 3)


def test_a_surface_guide_puts_fine_samples_at_each_surface_rays_depth_and_leaves_the_coarse_ones():
    torch.manual_seed(0)
    model = AffNeRF(replace(SMALL, coarse_field="shared"), num_classes=4)
    codes = model.encode(torch.rand(1, 3, 32, 32))
    origins = torch.tensor([[0.0, 0.0, 0.8], [0.05, 0.0, 0.8], [0.0, 0.8, 0.8], [0.02, 0.0, 0.8]])
    dirs = torch.tensor([[0.0, 0.0, -1.0]] * 4)  # the third passes beside the cube
    bg, obj = torch.full((4, 3), 0.5), torch.zeros(4, dtype=torch.long)
    guide = SurfaceGuide(torch.tensor([0.75, 0.0, 0.8, 0.7]), share=0.5, sigma=0.0)
    runs = []
    for g in (guide, None):
        generator = torch.Generator().manual_seed(3)
        runs.append(model.render_rays(codes, obj, origins, dirs, bg, True, generator, g))
    (coarse, fine), (plain_coarse, plain_fine) = runs
    torch.testing.assert_close(coarse.t, plain_coarse.t)
    assert (fine.t[0] == 0.75).sum() == 4 and (fine.t[3] == 0.7).sum() == 4  # half of the 8 fine samples
    torch.testing.assert_close(fine.t[1], plain_fine.t[1])  # depth 0: no surface, samples as without a guide
