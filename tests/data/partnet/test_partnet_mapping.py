"""The PartNet-Mobility -> affnerf table: shipped entries, lookup order, defaults, strictness, user files."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from affnerf.data.partnet.hierarchy import Leaf, read_leaves
from affnerf.data.partnet.mapping import category_mapping, leaf_affordance, load_mapping
from affnerf.errors import AffnerfError
from affnerf.objects.registry import CATEGORY_NAMES
from affnerf.vocab import AFFORDANCE_CLASSES

SHIPPED = {
    "StorageFurniture": ("cabinet", "support"),
    "Bottle": ("bottle", "grasp"),
    "Kettle": ("teapot", "contain"),
    "Bucket": ("bucket", "contain"),
    "Scissors": ("scissors", "grasp"),
    "Eyeglasses": ("eyeglasses", "grasp"),
    "Pen": ("pen", "grasp"),
}


def test_shipped_table_covers_the_categories() -> None:
    table = load_mapping()
    for cat, (category, default) in SHIPPED.items():
        assert (table[cat].category, table[cat].default) == (category, default)
    for entry in table.values():
        assert entry.category in CATEGORY_NAMES
        assert set(entry.parts.values()) <= set(AFFORDANCE_CLASSES[1:])


@pytest.mark.parametrize(
    ("cat", "name", "affordance"),
    [
        ("StorageFurniture", "handle", "pull"),
        ("StorageFurniture", "cabinet_door_surface", "open"),
        ("StorageFurniture", "drawer_front", "open"),
        ("StorageFurniture", "drawer_side", "open"),
        ("StorageFurniture", "shelf", "support"),
        ("Bottle", "lid", "open"),
        ("Bottle", "neck", "pour"),
        ("Bottle", "body", "grasp"),
        ("Kettle", "spout", "pour"),
        ("Kettle", "handle", "grasp"),
        ("Kettle", "lid", "open"),
        ("Kettle", "body", "contain"),
        ("Scissors", "blade", "cut"),
        ("Eyeglasses", "lens", "view"),
        ("Eyeglasses", "leg", "wear"),
        ("Pen", "tip", "write"),
        ("Pen", "cap", "open"),
    ],
)
def test_named_leaves(cat: str, name: str, affordance: str) -> None:
    entry = load_mapping()[cat]
    assert leaf_affordance(Leaf(1, name, (), ()), entry, Path("result.json"), strict=True) == affordance


def test_lookup_goes_through_ancestors_nearest_first() -> None:
    entry = load_mapping()["StorageFurniture"]
    in_frame = Leaf(39, "other_leaf", (), ("other", "cabinet_frame", "cabinet", "storage_furniture"))
    in_drawer = Leaf(40, "other_leaf", (), ("other", "drawer", "cabinet", "storage_furniture"))
    assert leaf_affordance(in_frame, entry, Path("result.json"), strict=True) == "support"
    assert leaf_affordance(in_drawer, entry, Path("result.json"), strict=True) == "open"
    # the leaf's own name wins over its ancestors'
    handle = Leaf(15, "handle", (), ("cabinet_door", "cabinet"))
    assert leaf_affordance(handle, entry, Path("result.json"), strict=True) == "pull"


def test_unnamed_leaf_takes_the_default_with_a_warning(caplog: pytest.LogCaptureFixture) -> None:
    entry = load_mapping()["Bottle"]
    leaf = Leaf(9, "sticker", (), ("normal_bottle", "bottle"))
    with caplog.at_level(logging.WARNING):
        assert leaf_affordance(leaf, entry, Path("x/result.json"), part_name="sticker") == "grasp"
    assert "'sticker'" in caplog.text and "x/result.json" in caplog.text
    with pytest.raises(AffnerfError, match=r"x/result.json: part 'sticker'"):
        leaf_affordance(leaf, entry, Path("x/result.json"), strict=True)


def test_user_file_merges_over_the_shipped_table(tmp_path: Path) -> None:
    user = tmp_path / "my_mapping.yaml"
    user.write_text(
        "StorageFurniture:\n  parts:\n    handle: grasp\n    Mystery_Panel: open\n"
        "Mug:\n  category: teapot\n  default: contain\n  parts:\n    handle: grasp\n"
        "Bottle:\n  default: pour\n"
    )
    table = load_mapping(user)
    cabinet = table["StorageFurniture"]
    assert cabinet.category == "cabinet" and cabinet.default == "support"
    assert cabinet.parts["handle"] == "grasp" and cabinet.parts["mystery_panel"] == "open"
    assert cabinet.parts["drawer_front"] == "open"  # shipped entries stay
    assert (table["Mug"].category, table["Mug"].parts) == ("teapot", {"handle": "grasp"})
    assert table["Bottle"].default == "pour" and table["Bottle"].parts["lid"] == "open"


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("Bottle:\n  parts:\n    lid: unscrew\n", "unknown affordance 'unscrew'"),
        ("Bottle:\n  default: twist\n", "unknown affordance 'twist'"),
        ("Mug:\n  parts:\n    handle: grasp\n", "needs 'category' and 'default'"),
        ("Bottle:\n  colour: red\n", "unknown keys"),
        ("Bottle: [1, 2\n", "not a valid YAML"),
        ("- Bottle\n", "YAML mapping"),
    ],
)
def test_bad_user_files_name_the_file(tmp_path: Path, text: str, problem: str) -> None:
    user = tmp_path / "bad_mapping.yaml"
    user.write_text(text)
    with pytest.raises(AffnerfError, match=problem) as info:
        load_mapping(user)
    assert str(info.value).startswith(str(user)) and "\n" not in str(info.value)


def test_missing_user_file(tmp_path: Path) -> None:
    with pytest.raises(AffnerfError, match="nope.yaml"):
        load_mapping(tmp_path / "nope.yaml")


def test_unknown_model_cat_names_meta_json() -> None:
    with pytest.raises(AffnerfError, match=r"obj/meta.json: model_cat 'Toaster'"):
        category_mapping(load_mapping(), "Toaster", Path("obj/meta.json"))


def test_fixture_hierarchy_leaves(toy_cabinet: Path) -> None:
    leaves = read_leaves(toy_cabinet / "result.json")
    assert [leaf.name for leaf in leaves] == [
        "other_leaf",
        "back_panel",
        "cabinet_door_surface",
        "handle",
        "drawer_front",
        "drawer_bottom",
        "handle",
    ]
    assert leaves[0].ancestors == ("other", "cabinet_frame", "cabinet", "storage_furniture")
    assert leaves[0].objs == ("original-1",)


def test_yaw_turns_imported_fronts_to_the_canonical_front(tmp_path: Path) -> None:
    assert load_mapping()["StorageFurniture"].yaw_deg == 90.0
    assert load_mapping()["Bottle"].yaw_deg == 0.0
    user = tmp_path / "m.yaml"
    user.write_text("StorageFurniture:\n  yaw_deg: -90\n")
    assert load_mapping(user)["StorageFurniture"].yaw_deg == -90.0
    user.write_text("StorageFurniture:\n  yaw_deg: left\n")
    with pytest.raises(AffnerfError, match=r"m\.yaml: entry 'StorageFurniture': 'yaw_deg' must be a number"):
        load_mapping(user)
