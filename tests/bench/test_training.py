"""Training-throughput measurements: one shared training step, timed with and without batch sampling."""

from __future__ import annotations

import torch

from affnerf.bench.curves import step_seconds
from affnerf.bench.training import step_throughput, training_step
from affnerf.data.dataset import Dataset
from affnerf.train.cache import cached_frames


def _frames(config):
    ds = Dataset.open(config.data)
    crop = config.model.encoder_resolution
    return [cached_frames(ds.load_object(e), config.cache_dir, config.image_scale, crop) for e in ds.objects("train")]


def test_a_training_step_changes_the_weights(tiny_train_config):
    config = tiny_train_config()
    step, model = training_step(config, _frames(config), torch.device("cpu"), batches=2)
    before = [p.detach().clone() for p in model.parameters()]
    step()
    assert any(not torch.equal(a, b) for a, b in zip(before, model.parameters(), strict=True))


def test_throughput_counts_rays_and_field_points(tiny_train_config):
    config = tiny_train_config()
    frames = _frames(config)
    out = step_throughput(config, frames, steps=2, device=torch.device("cpu"))
    seconds = out["seconds_per_step"]["median"]
    assert seconds > 0 and out["rays_per_second"] == config.rays_per_step / seconds
    assert out["points_per_step"] >= config.rays_per_step  # at least one field evaluation per ray
    assert step_seconds(config, frames, steps=2, warmup=1) > 0
