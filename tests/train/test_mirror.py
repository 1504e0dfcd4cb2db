"""Mirror augmentation: the plane each object is mirrored across, and flipped views that agree with mirrored rays."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from affnerf.data.dataset import Dataset
from affnerf.data.writer import surface_mesh_record
from affnerf.objects.asset import merge_parts
from affnerf.objects.registry import make_object
from affnerf.rendering.rays import pixel_rays
from affnerf.train.cache import cached_frames
from affnerf.train.config import SMALL
from affnerf.train.mirror import (
    flipped_crop_intrinsics,
    mirror_asymmetry,
    mirror_axis,
    mirrored_poses,
    reflection,
)
from affnerf.train.points import PointSet, make_point_set
from affnerf.train.sampler import PointSampler, RaySampler


def _shell(labels_of) -> PointSet:
    rng = np.random.default_rng(3)
    xyz = rng.normal(size=(4000, 3))
    xyz = (0.2 * xyz / np.linalg.norm(xyz, axis=1, keepdims=True)).astype(np.float32)  # a sphere's surface
    return PointSet(xyz, np.zeros(len(xyz), np.uint8), labels_of(xyz).astype(np.uint8), np.zeros(len(xyz), np.float16))


def test_the_axis_is_the_plane_whose_mirror_keeps_the_labels_and_none_without_one():
    assert mirror_axis(_shell(lambda p: np.where(p[:, 0] > 0.05, 1, 2))) == 1  # parts split along x: mirror y
    assert mirror_axis(_shell(lambda p: np.where(p[:, 1] > 0.05, 1, 2))) == 0
    quadrant = _shell(lambda p: np.where((p[:, 0] > 0) & (p[:, 1] > 0), 1, 2))
    assert min(mirror_asymmetry(quadrant, 0), mirror_asymmetry(quadrant, 1)) > 0.1
    lopsided = _shell(lambda p: np.where(p[:, 0] + p[:, 1] > 0, 1, 2))  # split by a diagonal plane
    assert mirror_axis(lopsided) == -1


@pytest.mark.parametrize(
    ("category", "axis"),
    # conventions §1: a pen's tip and a teapot's spout point along +x, eyeglasses and cabinets face -y
    [("pen", 1), ("teapot", 1), ("eyeglasses", 0), ("cabinet", 0)],
)
def test_procedural_objects_are_mirrored_without_turning_their_categorys_orientation(category, axis):
    mesh = surface_mesh_record(merge_parts(make_object(category, 5)))
    points = make_point_set(mesh, 0.25, (0.005, 0.02), seed=0, total=12000)
    assert mirror_axis(points) == axis


def test_a_flipped_crop_with_its_mirrored_camera_sees_the_mirrored_rays():
    rng = np.random.default_rng(0)
    angle = rng.uniform(0, 2 * np.pi)
    pose = np.eye(4)
    pose[:3, :3] = [[np.cos(angle), 0.0, np.sin(angle)], [np.sin(angle), 0.0, -np.cos(angle)], [0.0, 1.0, 0.0]]
    pose[:3, 3] = [0.3 * np.sin(angle), -0.3 * np.cos(angle), 0.2]
    size, intrinsics = 32, np.array([[40.0, 40.0, 15.0, 17.0]])
    pixels = rng.integers(0, size, (50, 2))
    signs = reflection(0)
    flipped_pose = mirrored_poses(pose[None], signs)[0]
    assert np.linalg.det(flipped_pose[:3, :3]) == pytest.approx(1.0)
    o, d = pixel_rays(torch.from_numpy(pixels), torch.from_numpy(intrinsics[0]), torch.from_numpy(pose))
    flipped = np.stack([size - 1 - pixels[:, 0], pixels[:, 1]], 1)
    k = flipped_crop_intrinsics(intrinsics, size)[0]
    o2, d2 = pixel_rays(torch.from_numpy(flipped), torch.from_numpy(k), torch.from_numpy(flipped_pose))
    np.testing.assert_allclose(o2.numpy(), o.numpy() * signs, atol=1e-12)
    np.testing.assert_allclose(d2.numpy(), d.numpy() * signs, atol=1e-12)


def _frames(train_dataset, tmp_path):
    ds = Dataset.open(train_dataset)
    return [cached_frames(ds.load_object(e), tmp_path, 1.0, 32) for e in ds.objects(split="train")]


def test_a_mirrored_object_gets_flipped_crops_and_mirrored_rays_and_chance_zero_keeps_the_draws(
    train_dataset, tmp_path
):
    frames = _frames(train_dataset, tmp_path)
    plain = RaySampler(frames, 2, 256, 0.5, seed=3).next_batch()
    axes = [1] * len(frames)
    zero = RaySampler(frames, 2, 256, 0.5, seed=3, mirror_fraction=0.0, mirror_axes=axes).next_batch()
    never = RaySampler(frames, 2, 256, 0.5, seed=3, mirror_fraction=1.0, mirror_axes=[-1] * len(frames)).next_batch()
    for same in (zero, never):
        assert torch.equal(same.origins, plain.origins) and torch.equal(same.images, plain.images)
        assert torch.equal(same.reflect, torch.ones(2, 3))
    mirrored = RaySampler(frames, 2, 256, 0.5, seed=3, mirror_fraction=1.0, mirror_axes=axes).next_batch()
    # the first object's views and rays are drawn before its mirror draw, so they are the plain batch's, mirrored
    assert mirrored.reflect.tolist() == [[1.0, -1.0, 1.0]] * 2
    assert torch.equal(mirrored.images[0], plain.images[0].flip(-1))
    first = plain.ray_object == 0
    assert torch.equal(mirrored.ray_object == 0, first) and torch.equal(mirrored.rgb[first], plain.rgb[first])
    signs = torch.tensor([1.0, -1.0, 1.0])
    torch.testing.assert_close(mirrored.origins[first], plain.origins[first] * signs)
    torch.testing.assert_close(mirrored.dirs[first], plain.dirs[first] * signs)
    with pytest.raises(ValueError, match="an axis for each object"):
        RaySampler(frames, 2, 256, 0.5, seed=3, mirror_fraction=0.5)


def test_the_point_sampler_mirrors_each_objects_points_by_its_signs():
    xyz = np.random.default_rng(0).uniform(-0.2, 0.2, (100, 3)).astype(np.float32)
    sets = {k: PointSet(xyz, np.zeros(100, np.uint8), np.ones(100, np.uint8), np.zeros(100, np.float16)) for k in "ab"}
    plain = PointSampler(sets, 10, seed=0).draw(["a", "b"])
    signs = np.array([[1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]])
    mirrored = PointSampler(sets, 10, seed=0).draw(["a", "b"], signs)
    torch.testing.assert_close(mirrored.points, plain.points * torch.from_numpy(signs).float()[plain.point_object])


def test_the_trainer_finds_each_objects_plane_and_trains_with_mirrored_views(tiny_train_config):
    from affnerf.train import distributed
    from affnerf.train.trainer import Trainer

    config = tiny_train_config(steps=3, points_weight=1.0, points_per_object=64, mirror_fraction=1.0)
    trainer = Trainer(config, distributed.Context(rank=0, world=1, device=torch.device("cpu")))
    trainer.setup()
    sampler = trainer.state.sampler
    screwdrivers = [
        a for f, a in zip(sampler.objects, sampler.mirror_axes, strict=True) if "screwdriver" in f.object_id
    ]
    assert screwdrivers and set(screwdrivers) == {1}  # shaft along +x: mirrored across y = 0
    assert all(axis in (0, 1) for axis in sampler.mirror_axes)  # bottles are symmetric about both planes
    summary = trainer.train()
    assert summary.step == 3 and np.isfinite(summary.scalars["loss/total"])
    assert SMALL.mirror_fraction == 0.0


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--mirror-fraction", "1.5"], "--mirror-fraction is a chance in [0, 1]"),
        (["--mirror-fraction", "0.5", "--points-weight", "0"], "--mirror-fraction needs --points-weight > 0"),
        (["--mirror-fraction", "0.5", "--model.kind", "pixelnerf"], "--mirror-fraction needs global codes"),
    ],
)
def test_mirror_options_that_cannot_work_are_refused_with_one_line(tmp_path, capsys, options, message):
    from affnerf.cli.main import main

    argv = ["train", "--data", str(tmp_path), "--out", str(tmp_path / "run"), "--config", "small", "--steps", "10"]
    assert main([*argv, *options]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
