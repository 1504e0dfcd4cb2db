"""Importing PartNet-Mobility objects into datasets."""

from __future__ import annotations

import json
import shutil

import numpy as np

from affnerf.data.dataset import Dataset
from affnerf.data.importer import ImportConfig, import_partnet
from affnerf.data.partnet import write_partnet_fixture
from affnerf.vocab import AFFORDANCE_CLASSES


def test_fixture_import_creates_a_readable_dataset(tmp_path):
    src = write_partnet_fixture(tmp_path / "toy")
    entries = import_partnet([src], ImportConfig(out=tmp_path / "ds", views=4, width=64, height=48), progress=False)
    assert [e.split for e in entries] == ["test"]
    ds = Dataset.open(tmp_path / "ds")
    obj = ds.load_object(entries[0])
    assert obj.record.category == "cabinet" and obj.record.extra["source"] == "partnet-mobility"
    assert obj.record.extra["scale"] > 0 and obj.record.extra["joints"]
    seen = set()
    for i in range(len(obj)):
        seen |= set(np.unique(obj.affordance(i)).tolist())
    assert {AFFORDANCE_CLASSES.index(a) for a in ("open", "support")} <= seen


def test_import_into_an_existing_dataset_keeps_its_objects(tmp_path, tiny_dataset):
    root = tmp_path / "ds"
    shutil.copytree(tiny_dataset, root)
    before = json.loads((root / "dataset.json").read_text())
    src = write_partnet_fixture(tmp_path / "toy")
    import_partnet([src], ImportConfig(out=root, views=2, width=32, height=24, split="unseen"), progress=False)
    after = json.loads((root / "dataset.json").read_text())
    assert after["generation"] == before["generation"]
    assert len(after["objects"]) == len(before["objects"]) + 1
    assert {o["split"] for o in after["objects"] if o["source"] == "partnet-mobility"} == {"unseen"}


def test_random_joint_states_get_their_own_ids(tmp_path):
    src = write_partnet_fixture(tmp_path / "toy")
    cfg = ImportConfig(out=tmp_path / "ds", views=1, width=32, height=24, joint_state="random", seed=4)
    (entry,) = import_partnet([src], cfg, progress=False)
    assert entry.id.endswith("_s4")


def test_shared_objects_render_with_their_affordances(tmp_path, shared_partnet):
    cfg = ImportConfig(out=tmp_path / "ds", views=6, width=96, height=72)
    entries = import_partnet([shared_partnet / "40147", shared_partnet / "3763"], cfg, progress=False)
    ds = Dataset.open(tmp_path / "ds")
    want = {"cabinet": {"pull", "open", "support"}, "bottle": {"grasp", "pour", "open"}}
    for entry in entries:
        obj = ds.load_object(entry)
        seen = set()
        for i in range(len(obj)):
            seen |= {AFFORDANCE_CLASSES[c] for c in np.unique(obj.affordance(i)).tolist() if c}
        assert seen == want[entry.category], entry.id
        textured = obj.rgb(0)[obj.part(0) > 0]
        assert textured.std() > 5  # textures and shading, not one flat colour
