"""Dataset generation: splits, shards, resuming, determinism."""

from __future__ import annotations

import filecmp
import json
import os

import pytest

from affnerf.data.dataset import Dataset
from affnerf.data.generate import generate_dataset, instance_splits, plan_jobs, split_counts
from affnerf.data.index import rebuild_index
from affnerf.data.writer import PARTIAL_DIR
from affnerf.errors import AffnerfError


def _same_tree(a, b):
    cmp = filecmp.dircmp(a, b)
    assert not cmp.left_only and not cmp.right_only, (cmp.left_only, cmp.right_only)
    _, mismatch, errors = filecmp.cmpfiles(a, b, cmp.common_files, shallow=False)
    assert not mismatch and not errors, (a, mismatch)
    for sub in cmp.common_dirs:
        _same_tree(a / sub, b / sub)


def test_splits_are_80_10_10_per_category_and_unseen_categories_are_kept_out(tmp_path, tiny_config):
    assert split_counts(10) == (8, 1, 1) and split_counts(20) == (16, 2, 2) and split_counts(100) == (80, 10, 10)
    splits = instance_splits(0, "pen", 20)
    assert sorted(splits) == sorted(["train"] * 16 + ["val"] * 2 + ["test"] * 2)
    jobs = plan_jobs(tiny_config(tmp_path, objects_per_category=10, unseen="pen"))
    pens = {j.entry.split for j in jobs if j.entry.category == "pen"}
    drivers = [j.entry.split for j in jobs if j.entry.category == "screwdriver"]
    assert pens == {"unseen"}
    assert sorted(drivers) == sorted(["train"] * 8 + ["val", "test"])


def test_shards_are_disjoint_and_together_make_the_same_dataset(tmp_path, tiny_dataset, tiny_config):
    root = tmp_path / "sharded"
    for i in range(3):
        generate_dataset(tiny_config(root, shard=f"{i}/3"), progress=False)
    ids = [{j.entry.id for j in plan_jobs(tiny_config(root))[i::3]} for i in range(3)]
    assert not (ids[0] & ids[1]) and not (ids[1] & ids[2]) and not (ids[0] & ids[2])
    _same_tree(root / "pen", tiny_dataset / "pen")
    _same_tree(root / "screwdriver", tiny_dataset / "screwdriver")
    assert (
        json.loads((root / "dataset.json").read_text())["objects"]
        == json.loads((tiny_dataset / "dataset.json").read_text())["objects"]
    )


def test_two_workers_write_the_same_bytes(tmp_path, tiny_dataset, tiny_config):
    root = tmp_path / "parallel"
    generate_dataset(tiny_config(root, workers=2), progress=False)
    _same_tree(root / "pen", tiny_dataset / "pen")


def test_rerun_skips_finished_objects_and_recovers_from_an_interruption(tmp_path, tiny_config):
    root = tmp_path / "resumable"
    config = tiny_config(root, categories="pen")
    generate_dataset(config, progress=False)
    # simulate a run killed while writing pen_0001: its folder half-written in .partial, never renamed
    victim = root / "pen" / "pen_0001"
    os.rename(victim, root / PARTIAL_DIR / "pen_0001.999.dead")
    (root / PARTIAL_DIR / "pen_0001.999.dead" / "transforms.json").unlink()
    rebuild_index(root)
    assert [o.id for o in Dataset.open(root).objects()] == ["pen_0000", "pen_0002"]
    before = (root / "pen" / "pen_0000" / "transforms.json").stat().st_mtime_ns
    report = generate_dataset(config, progress=False)
    assert report.made == ["pen_0001"] and sorted(report.skipped) == ["pen_0000", "pen_0002"]
    assert (root / "pen" / "pen_0000" / "transforms.json").stat().st_mtime_ns == before
    assert not list((root / PARTIAL_DIR).iterdir())
    assert [o.id for o in Dataset.open(root).objects()] == ["pen_0000", "pen_0001", "pen_0002"]


def test_rerun_with_other_settings_is_refused(tmp_path, tiny_config):
    root = tmp_path / "settings"
    generate_dataset(tiny_config(root, categories="pen", objects_per_category=1), progress=False)
    with pytest.raises(AffnerfError, match=r"dataset\.json: generated with views=5, not 6"):
        generate_dataset(tiny_config(root, categories="pen", objects_per_category=1, views=6), progress=False)


def test_index_rebuild_lists_exactly_the_complete_folders(tiny_dataset, tmp_path):
    index = rebuild_index(tiny_dataset)
    assert len(index.objects) == 6
    assert json.loads((tiny_dataset / "dataset.json").read_text())["generation"]["seed"] == 3


@pytest.mark.parametrize("shard", ["3/3", "1/0", "a/b", "1"])
def test_bad_shard_is_refused(tmp_path, shard, tiny_config):
    with pytest.raises(AffnerfError, match="shard"):
        generate_dataset(tiny_config(tmp_path / "x", shard=shard), progress=False)


def test_a_failing_worker_stops_the_run_and_keeps_the_index_whole(tmp_path, tiny_config):
    root = tmp_path / "failing"
    root.mkdir()
    (root / "pen").write_text("not a folder")  # every pen object fails to be placed
    with pytest.raises(OSError):
        generate_dataset(tiny_config(root, workers=2), progress=False)
    listed = [o.id for o in Dataset.open(root).objects()] if (root / "dataset.json").exists() else []
    assert all(i.startswith("screwdriver") for i in listed)
    for oid in listed:
        assert (root / "screwdriver" / oid / "transforms.json").is_file()
