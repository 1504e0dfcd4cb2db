"""Importing PartNet-Mobility objects into datasets."""

from __future__ import annotations

import json
import re
import shutil
from dataclasses import replace

import numpy as np
import pytest

from affnerf.data.dataset import Dataset
from affnerf.data.importer import ImportConfig, import_partnet
from affnerf.data.partnet import write_partnet_fixture
from affnerf.errors import AffnerfError
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


def _tree(root) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.mark.parametrize(
    "change, problem",
    [
        ({"views": 3}, "views=2, not 3"),
        ({"width": 40}, "width=32, not 40"),
        ({"seed": 5}, "seed=0, not 5"),
        ({"split": "train"}, "split='test', not 'train'"),
        ({"mapping": "edited"}, "mapping_sha256="),
    ],
)
def test_reimport_with_other_settings_is_refused_and_keeps_the_first_copy(tmp_path, change, problem):
    src = write_partnet_fixture(tmp_path / "toy")
    mapping = tmp_path / "mapping.yaml"
    mapping.write_text("StorageFurniture:\n  parts:\n    handle: pull\n")
    first = ImportConfig(out=tmp_path / "ds", views=2, width=32, height=24, mapping=mapping)
    (entry,) = import_partnet([src], first, progress=False)
    before = _tree(tmp_path / "ds")
    if change.get("mapping") == "edited":
        mapping.write_text("StorageFurniture:\n  parts:\n    handle: grasp\n")
        second = first
    else:
        second = replace(first, **change)
    with pytest.raises(AffnerfError, match=rf"{entry.id}/transforms\.json: already imported with {re.escape(problem)}"):
        import_partnet([src], second, progress=False)
    assert _tree(tmp_path / "ds") == before  # nothing written, nothing lost


def test_reimport_with_the_same_settings_keeps_the_copy_and_overwrite_replaces_it(tmp_path):
    src = write_partnet_fixture(tmp_path / "toy")
    first = ImportConfig(out=tmp_path / "ds", views=2, width=32, height=24)
    (entry,) = import_partnet([src], first, progress=False)
    folder = tmp_path / "ds" / entry.path
    before = _tree(tmp_path / "ds")
    assert import_partnet([src], first, progress=False) == [entry]
    assert _tree(tmp_path / "ds") == before
    import_partnet([src], replace(first, views=3, width=40, overwrite=True), progress=False)
    record = json.loads((folder / "transforms.json").read_text())
    assert len(record["frames"]) == 3 and record["w"] == 40
    assert sorted(p.name for p in (folder / "rgb").iterdir()) == ["000.png", "001.png", "002.png"]
    assert Dataset.open(tmp_path / "ds").load_object(entry.id).rgb(2).shape == (24, 40, 3)
    assert not list((tmp_path / "ds" / ".partial").glob("*"))  # the old copy is gone, no debris
    index = json.loads((tmp_path / "ds" / "dataset.json").read_text())
    assert [o["id"] for o in index["objects"]] == [entry.id]
