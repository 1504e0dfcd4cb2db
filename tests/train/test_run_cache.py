from dataclasses import replace

import torch

from affnerf.train import distributed as dist_utils
from affnerf.train import run_cache
from affnerf.train.config import SMALL
from affnerf.train.run_cache import cache_dir, made_by_ranks


def test_each_rank_makes_its_share_first_then_every_object_in_order(monkeypatch, tmp_path):
    waited = []
    monkeypatch.setattr(run_cache.dist_utils, "barrier", lambda ctx: waited.append(ctx.rank))
    made = []
    ctx = dist_utils.Context(rank=1, world=2, device=torch.device("cpu"))
    config = replace(SMALL, progress=False, out=tmp_path)
    out = made_by_ranks(list("abcde"), lambda e: made.append(e) or e.upper(), "x", config, ctx)
    assert made == ["b", "d", "a", "b", "c", "d", "e"]  # rank 1 of 2: its share, then all after the barrier
    assert waited == [1] and out == list("ABCDE")


def test_the_cache_is_beside_the_run_unless_a_folder_is_given(tmp_path):
    assert cache_dir(replace(SMALL, out=tmp_path)) == tmp_path / "cache"
    assert cache_dir(replace(SMALL, out=tmp_path, cache_dir=tmp_path / "shared")) == tmp_path / "shared"
