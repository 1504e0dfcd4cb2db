"""The demo on a tiny model: every example gets its outputs and the report links them."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
from PIL import Image

from affnerf.demo.examples import write_examples
from affnerf.demo.runner import DemoConfig, run_examples


def test_examples_are_rendered_for_every_category_and_the_fixture(tmp_path):
    files = write_examples(tmp_path, seed=0, objects_per_category=5)
    assert len(files) == 9 and files[-1].name == "partnet_fixture.png"
    for f in files:
        image = np.asarray(Image.open(f))
        assert image.shape == (300, 400, 3)
        assert 0.005 < (image.min(axis=2) < 250).mean() < 0.9  # an object on white


def test_demo_report_links_every_output(trained_runs, train_dataset, tmp_path):
    examples = tmp_path / "examples"
    examples.mkdir()
    from affnerf.data.dataset import Dataset

    ds = Dataset.open(train_dataset)
    for entry in ds.objects(split="test"):
        Image.fromarray(ds.load_object(entry).rgb(0)).resize((160, 120)).save(examples / f"{entry.id}.png")
    config = replace(DemoConfig(out=tmp_path / "out"), views=2, grasps=2, device="cpu")
    report = run_examples(config, trained_runs["affnerf"], examples)
    page = report.read_text()
    assert page.count('class="example"') == 2
    for src in re.findall(r'src="([^"]+)"', page):
        assert (report.parent / src).is_file(), src
    assert "Model quality on held-out objects" in page
