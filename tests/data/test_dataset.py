"""Dataset helpers that do not need files."""

from __future__ import annotations

from affnerf.data.dataset import interleave_categories
from affnerf.data.format import IndexEntry


def _entries(spec: str) -> list[IndexEntry]:
    return [
        IndexEntry(id=f"{cat}_{i}", category=cat, path=f"{cat}_{i}", split="test", source="procedural")
        for i, cat in enumerate(spec.split())
    ]


def test_interleave_takes_categories_in_turn_by_name():
    ordered = interleave_categories(_entries("pen pen pen bottle cabinet cabinet"))
    assert [e.category for e in ordered] == ["bottle", "cabinet", "pen", "cabinet", "pen", "pen"]
    assert [e.id for e in ordered if e.category == "pen"] == ["pen_0", "pen_1", "pen_2"]  # order kept within one


def test_interleave_caps_each_category():
    ordered = interleave_categories(_entries("pen pen pen bottle"), per_category=2)
    assert [e.id for e in ordered] == ["bottle_3", "pen_0", "pen_1"]
    assert interleave_categories([]) == []
