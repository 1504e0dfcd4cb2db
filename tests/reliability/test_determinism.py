"""The same seed gives byte-identical datasets and, on the CPU, identical training losses."""

from __future__ import annotations

import filecmp
import json

from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.train.trainer import train


def test_same_seed_same_bytes(tmp_path):
    trees = []
    for name in ("a", "b"):
        root = tmp_path / name
        generate_dataset(
            GenerateConfig(
                out=root,
                categories="cabinet,teapot",
                objects_per_category=2,
                views=3,
                width=48,
                height=36,
                seed=11,
                workers=2 if name == "b" else 1,
            ),
            progress=False,
        )
        trees.append(root)
    files = sorted(p.relative_to(trees[0]) for p in trees[0].rglob("*") if p.is_file() and p.name != ".dataset.lock")
    assert len(files) > 20
    _, mismatch, errors = filecmp.cmpfiles(trees[0], trees[1], [str(f) for f in files], shallow=False)
    assert not mismatch and not errors


def test_same_seed_same_losses(tiny_train_config, tmp_path):
    runs = [tiny_train_config(out=tmp_path / name, steps=15) for name in ("a", "b")]
    for config in runs:
        train(config)
    losses = [
        [json.loads(line)["loss/total"] for line in (c.out / "metrics.jsonl").read_text().splitlines()] for c in runs
    ]
    assert len(losses[0]) == 15 and losses[0] == losses[1]
