"""The paper's sampling rule and the data walk."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from affnerf.data.dataset import Dataset
from affnerf.train.cache import cached_frames
from affnerf.train.config import PAPER, SMALL
from affnerf.train.sampler import RaySampler


def _frames(train_dataset, tmp_path):
    ds = Dataset.open(train_dataset)
    return [cached_frames(ds.load_object(e), tmp_path, 1.0, 32) for e in ds.objects(split="train")]


def test_the_encoded_view_is_never_a_target_view(train_dataset, tmp_path):
    sampler = RaySampler(_frames(train_dataset, tmp_path), 2, 256, 0.5, seed=0)
    for _ in range(30):
        batch = sampler.next_batch()
        enc = batch.encoder_view[batch.ray_object, 0]
        assert np.all((batch.ray_view != enc).numpy())
        assert batch.images.shape == (2, 1, 3, 32, 32) and batch.origins.shape == (256, 3)


def test_several_encoded_views_are_distinct_and_never_targets(train_dataset, tmp_path):
    sampler = RaySampler(_frames(train_dataset, tmp_path), 2, 256, 0.5, seed=0, input_views=3)
    for _ in range(10):
        batch = sampler.next_batch()
        assert batch.images.shape == (2, 3, 3, 32, 32) and batch.input_poses.shape == (2, 3, 4, 4)
        for b in range(2):
            enc = set(batch.encoder_view[b].tolist())
            assert len(enc) == 3
            assert not enc & set(batch.ray_view[batch.ray_object == b].tolist())


def test_rays_match_the_cached_pixels_and_foreground_share(train_dataset, tmp_path):
    frames = _frames(train_dataset, tmp_path)
    sampler = RaySampler(frames, 2, 2000, 1.0, seed=1)
    batch = sampler.next_batch()
    on_object = (batch.labels > 0).float().mean().item()
    assert on_object == 1.0  # every ray drawn on the object
    uniform = RaySampler(frames, 2, 2000, 0.0, seed=1).next_batch()
    assert (uniform.labels > 0).float().mean().item() < 0.5


def test_outline_rays_take_the_uniform_share_and_zero_keeps_the_paper_draws(train_dataset, tmp_path):
    frames = _frames(train_dataset, tmp_path)
    plain = RaySampler(frames, 2, 2000, 0.5, seed=4).next_batch()
    zero = RaySampler(frames, 2, 2000, 0.5, seed=4, outline_fraction=0.0, outline_radius=3).next_batch()
    np.testing.assert_array_equal(plain.origins.numpy(), zero.origins.numpy())
    near = RaySampler(frames, 2, 2000, 0.5, seed=4, outline_fraction=0.5, outline_radius=2).next_batch()
    assert (near.labels > 0).float().mean() > (plain.labels > 0).float().mean() + 0.1
    with pytest.raises(ValueError, match="sum to at most 1"):
        RaySampler(frames, 2, 8, 0.7, seed=0, outline_fraction=0.4)


def _second_class_share(batch) -> float:
    """Share of a batch's object rays whose label is not their object's most frequent one among them."""
    shares = []
    for b in range(len(batch.object_ids)):
        labels = batch.labels[(batch.ray_object == b) & (batch.labels > 0)].numpy()
        shares.append(1.0 - np.bincount(labels).max() / len(labels))
    return float(np.mean(shares))


def test_edge_rays_take_the_foreground_share_and_zero_keeps_the_draws(train_dataset, tmp_path):
    frames = _frames(train_dataset, tmp_path)
    plain = RaySampler(frames, 2, 2000, 0.5, seed=4, outline_fraction=0.4).next_batch()
    zero = RaySampler(frames, 2, 2000, 0.5, seed=4, outline_fraction=0.4, edge_fraction=0.0).next_batch()
    np.testing.assert_array_equal(plain.origins.numpy(), zero.origins.numpy())
    edged = RaySampler(frames, 2, 2000, 0.5, seed=4, outline_fraction=0.4, edge_fraction=0.5).next_batch()
    assert edged.object_ids == plain.object_ids
    assert _second_class_share(edged) > _second_class_share(plain) + 0.05  # both sides of the parts' edges
    with pytest.raises(ValueError, match="part edges' share"):
        RaySampler(frames, 2, 8, 0.3, seed=0, edge_fraction=0.4)


def test_cut_input_weight_zero_encodes_only_whole_views_and_one_keeps_the_draws(train_dataset, tmp_path):
    frames = []
    for f in _frames(train_dataset, tmp_path):  # the object runs off the left edge in every even frame
        labels = np.array(f.labels)
        labels[::2, :, 0] = 1
        frames.append(dataclasses.replace(f, labels=labels))
    plain = RaySampler(frames, 2, 64, 0.5, seed=3)
    ones = RaySampler(frames, 2, 64, 0.5, seed=3, cut_input_weight=1.0)
    whole = RaySampler(frames, 2, 64, 0.5, seed=3, cut_input_weight=0.0)
    for _ in range(20):
        a, b, c = plain.next_batch(), ones.next_batch(), whole.next_batch()
        np.testing.assert_array_equal(a.origins.numpy(), b.origins.numpy())
        assert (c.encoder_view.numpy() % 2 == 1).all()
    with pytest.raises(ValueError, match="cut input views' weight"):
        RaySampler(frames, 2, 8, 0.5, seed=0, cut_input_weight=1.5)


def test_each_epoch_visits_every_object_and_ranks_split_them(train_dataset, tmp_path):
    frames = _frames(train_dataset, tmp_path)
    n = len(frames)
    seen = []
    sampler = RaySampler(frames, 1, 8, 0.5, seed=2)
    for _ in range(n):
        seen += sampler.next_batch().object_ids
    assert sorted(seen) == sorted(f.object_id for f in frames)
    ranks = [RaySampler(frames, 1, 8, 0.5, seed=2, rank=r, world=2) for r in range(2)]
    first = [set(r.next_batch().object_ids) for r in ranks]
    assert not (first[0] & first[1])


def test_state_round_trip_continues_the_same_batches(train_dataset, tmp_path):
    frames = _frames(train_dataset, tmp_path)
    a = RaySampler(frames, 2, 64, 0.5, seed=3)
    for _ in range(5):
        a.next_batch()
    b = RaySampler(frames, 2, 64, 0.5, seed=3)
    b.load_state_dict(a.state_dict())
    for _ in range(7):
        x, y = a.next_batch(), b.next_batch()
        assert x.object_ids == y.object_ids
        np.testing.assert_array_equal(x.origins.numpy(), y.origins.numpy())
        np.testing.assert_array_equal(x.labels.numpy(), y.labels.numpy())


def test_the_input_crops_depth_is_the_objects_depth_where_the_crops_show_it(train_dataset, tmp_path):
    frames = _frames(train_dataset, tmp_path)
    batch = RaySampler(frames, 2, 64, 0.5, seed=0, input_views=2).next_batch()
    assert batch.input_depth.shape == (2, 2, 32, 32)
    for b in range(2):
        obj = next(f for f in frames if f.object_id == batch.object_ids[b])
        background = np.asarray(obj.background, np.float32)
        shows_object = np.abs(batch.images[b].permute(0, 2, 3, 1).numpy() - background).max(-1) > 0.05
        has_depth = batch.input_depth[b].numpy() > 0
        assert (shows_object == has_depth).mean() > 0.9 and 0.05 < has_depth.mean() < 0.9
        assert has_depth.any() and (batch.input_depth[b][batch.input_depth[b] > 0] < 3.0).all()
        # the crops' labels come from the same pixels: an object where there is depth, background elsewhere
        np.testing.assert_array_equal(batch.input_labels[b].numpy() > 0, has_depth)


def test_a_sampler_without_input_views_gives_empty_inputs_and_full_ray_batches(train_dataset, tmp_path):
    # Semantic-NeRF fits one object from its targets alone: no encoder views, so no input crops or depths.
    batch = RaySampler(_frames(train_dataset, tmp_path)[:1], 1, 64, 0.5, seed=0, input_views=0).next_batch()
    assert batch.images.shape == (1, 0, 3, 32, 32) and batch.input_depth.shape == (1, 0, 32, 32)
    assert batch.input_labels.shape == (1, 0, 32, 32)
    assert batch.origins.shape == (64, 3) and batch.encoder_view.shape == (1, 0)


@pytest.mark.parametrize(
    ("shares", "message"),
    [
        (["--foreground-fraction", "0.7", "--outline-fraction", "0.4"], "--outline-fraction are shares >= 0 summing"),
        (["--foreground-fraction", "0.3", "--edge-fraction", "0.4"], "--edge-fraction is a share of the"),
        (["--cut-input-weight", "-0.1"], "--cut-input-weight is in [0, 1]"),
    ],
)
def test_ray_shares_out_of_range_are_refused_with_one_line(tmp_path, capsys, shares, message):
    from affnerf.cli.main import main

    argv = ["train", "--data", str(tmp_path), "--out", str(tmp_path / "run"), "--steps", "10"]
    assert main([*argv, *shares]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def test_the_trainer_draws_the_configs_outline_and_edge_rays(tiny_train_config):
    import torch

    from affnerf.train import distributed
    from affnerf.train.trainer import Trainer

    cpu = distributed.Context(rank=0, world=1, device=torch.device("cpu"))
    trainer = Trainer(tiny_train_config(steps=1, outline_fraction=0.4, outline_radius=2), cpu)
    trainer.setup()
    sampler = trainer.state.sampler
    assert (sampler.foreground_fraction, sampler.outline_fraction, sampler.outline_radius) == (0.5, 0.4, 2)
    edged = Trainer(tiny_train_config(steps=1, edge_fraction=0.2, edge_radius=2), cpu)
    edged.setup()
    assert (edged.state.sampler.edge_fraction, edged.state.sampler.edge_radius) == (0.2, 2)
    whole = Trainer(tiny_train_config(steps=1, cut_input_weight=0.0), cpu)
    whole.setup()
    assert whole.state.sampler.cut_input_weight == 0.0 and SMALL.cut_input_weight == 1.0
    assert SMALL.outline_fraction == 0.4 and PAPER.outline_fraction == 0.0


def test_checker_crops_mark_where_a_cut_frames_crop_leaves_it_as_evaluation_does(train_dataset, tmp_path):
    from affnerf.data.crop import touches_border
    from affnerf.model.config import ModelConfig
    from affnerf.model.inputs import dataset_views
    from affnerf.train.sampler import encoder_crops

    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects(split="train")[0])
    frames = cached_frames(obj, tmp_path, 1.0, 32)
    cut = [v for v in range(len(frames)) if touches_border(obj.affordance(v) > 0)]
    whole = [v for v in range(len(frames)) if v not in cut]
    assert whole and cut
    for v in whole[:2] + cut[:2]:
        plain = encoder_crops(frames, np.array([v]))[0]
        marked = encoder_crops(frames, np.array([v]), "checker")[0]
        config = ModelConfig(encoder_resolution=32, crop_outside="checker")
        evaluated = dataset_views(obj, [v], config)[0][0, 0].permute(1, 2, 0).numpy()
        np.testing.assert_array_equal(marked, np.round(evaluated * 255).astype(np.uint8))  # one crop rule everywhere
        assert v not in cut or (marked != plain).any()  # a cut object's crop always leaves its frame
