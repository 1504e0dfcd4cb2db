"""Example input images: one per category, rendered by the project from held-out objects, and the
PartNet-Mobility-format fixture rendered the same way."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X, Intrinsics, look_at
from affnerf.data.generate import instance_splits
from affnerf.data.raycast import FrameCaster
from affnerf.objects.asset import ObjectAsset, merge_parts
from affnerf.objects.registry import CATEGORY_NAMES, make_object, object_seed

#: The camera of the examples: in the band the training cameras come from (conventions §1), from the front-left.
EXAMPLE_EYE = 0.62 * np.array(
    [
        np.cos(np.radians(35)) * np.cos(np.radians(-115)),
        np.cos(np.radians(35)) * np.sin(np.radians(-115)),
        np.sin(np.radians(35)),
    ]
)


def held_out_index(seed: int, category: str, objects_per_category: int) -> int:
    """The first test-split instance of a category in a dataset generated with ``seed`` and that many objects."""
    splits = instance_splits(seed, category, objects_per_category)
    return splits.index("test") if "test" in splits else objects_per_category - 1


def render_example(asset: ObjectAsset, width: int = 400, height: int = 300) -> np.ndarray:
    """(H, W, 3) uint8 picture of an object on white from the example camera."""
    intr = Intrinsics.from_fov(width, height, DEFAULT_CAMERA_ANGLE_X)
    return FrameCaster(merge_parts(asset)).cast_frame(intr, look_at(EXAMPLE_EYE, np.zeros(3))).rgb


def write_examples(out: Path, seed: int = 0, objects_per_category: int = 20) -> list[Path]:
    """Write ``<category>.png`` for every category (a held-out instance of the dataset ``seed`` /
    ``objects_per_category``) and ``partnet_fixture.png``; returns the files."""
    from affnerf.data.partnet import load_partnet_object, write_partnet_fixture

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    for category in CATEGORY_NAMES:
        index = held_out_index(seed, category, objects_per_category)
        asset = make_object(category, object_seed(seed, category, index).spawn(2)[0])
        path = out / f"{category}.png"
        Image.fromarray(render_example(asset)).save(path)
        files.append(path)
    with tempfile.TemporaryDirectory() as tmp:
        fixture = load_partnet_object(write_partnet_fixture(Path(tmp) / "toy"))
        path = out / "partnet_fixture.png"
        Image.fromarray(render_example(fixture)).save(path)
        files.append(path)
    return files
