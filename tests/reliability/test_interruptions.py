"""SIGKILL mid-run, then a rerun or ``--resume``: nothing lost, nothing half-done counted, exact continuation.
Failed writes leave what was there before."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest
import torch
from support import train_argv

from affnerf.data.dataset import Dataset
from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.errors import AffnerfError
from affnerf.train import checkpoint as checkpoint_module
from affnerf.train.trainer import train


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "affnerf.cli.main", *args]


def _kill_when(proc: subprocess.Popen, ready, timeout: float = 120.0) -> None:
    """SIGKILL the process (and its children) as soon as ``ready()`` holds."""
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None and not ready():
        time.sleep(0.05)
    assert proc.poll() is None, "finished before it could be interrupted"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()


def _train_cli(config, out: Path, steps: int, *extra: str) -> list[str]:
    run = replace(config, out=out, steps=steps, checkpoint_every=5, log_every=1, val_every=0)
    return _cli(*train_argv(run, *extra))


def test_sigkill_during_training_then_resume_gives_the_uninterrupted_weights(tiny_train_config, tmp_path):
    config = tiny_train_config()
    steps = 20
    straight = tmp_path / "straight"
    subprocess.run(_train_cli(config, straight, steps), check=True, timeout=300)
    killed = tmp_path / "killed"
    proc = subprocess.Popen(_train_cli(config, killed, steps), start_new_session=True)
    _kill_when(proc, lambda: (killed / "checkpoints" / "step_00000005.pt").exists())
    assert not (killed / "checkpoints" / f"step_{steps:08d}.pt").exists()
    left = sorted(p.name for p in (killed / "checkpoints").iterdir())  # what the resume starts from
    subprocess.run(_train_cli(config, killed, steps, "--resume"), check=True, timeout=300)
    a = torch.load(straight / "checkpoints" / f"step_{steps:08d}.pt", weights_only=True)["model"]
    b = torch.load(killed / "checkpoints" / f"step_{steps:08d}.pt", weights_only=True)["model"]
    differ = {k: float((a[k].double() - b[k].double()).abs().max()) for k in a if not torch.equal(a[k], b[k])}
    assert not differ, f"resumed from {left}: {len(differ)} of {len(a)} tensors differ, largest {max(differ.values())}"


def test_sigkill_during_generation_then_rerun_completes_with_whole_objects(tmp_path):
    out = tmp_path / "ds"
    args = _cli(
        "data",
        "generate",
        "--out",
        str(out),
        "--categories",
        "screwdriver,pen",
        "--objects-per-category",
        "4",
        "--views",
        "12",
        "--width",
        "64",
        "--height",
        "48",
        "--workers",
        "2",
    )
    proc = subprocess.Popen(args, start_new_session=True, stderr=subprocess.DEVNULL)
    _kill_when(
        proc,
        lambda: (out / "dataset.json").exists() and len(json.loads((out / "dataset.json").read_text())["objects"]) >= 2,
    )
    listed = {o["id"] for o in json.loads((out / "dataset.json").read_text())["objects"]}
    assert len(listed) < 8
    for oid in listed:  # whatever is listed is whole
        obj = Dataset.open(out).load_object(oid)
        assert all((obj.folder / f.file_path).is_file() for f in obj.record.frames)
    subprocess.run(args, check=True, timeout=300, stderr=subprocess.DEVNULL)
    ds = Dataset.open(out)
    assert len(ds.objects()) == 8
    for entry in ds.objects():
        obj = ds.load_object(entry)
        assert len(obj) == 12 and obj.rgb(11).shape == (48, 64, 3)
    assert not any((out / ".partial").iterdir())


def test_sigkill_during_import_then_rerun(tmp_path):
    from affnerf.data.partnet import write_partnet_fixture

    sources = [str(write_partnet_fixture(tmp_path / f"toy{i}")) for i in range(3)]
    out = tmp_path / "ds"
    args = _cli(
        "data", "import-partnet", *sources, "--out", str(out), "--views", "40", "--width", "120", "--height", "90"
    )
    proc = subprocess.Popen(args, start_new_session=True, stderr=subprocess.DEVNULL)
    _kill_when(proc, lambda: (out / "dataset.json").exists())
    subprocess.run(args, check=True, timeout=300, stderr=subprocess.DEVNULL)
    ds = Dataset.open(out)
    assert len(ds.objects()) == 3
    for entry in ds.objects():
        obj = ds.load_object(entry)
        assert len(obj) == 40 and all((obj.folder / f.part_file_path).is_file() for f in obj.record.frames)


def test_failed_checkpoint_write_keeps_the_previous_checkpoint(tiny_train_config, monkeypatch):
    config = tiny_train_config(steps=10, checkpoint_every=5)
    train(config)
    folder = config.out / "checkpoints"
    before = {p.name: p.read_bytes() for p in folder.iterdir()}

    def disk_full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(checkpoint_module.torch, "save", disk_full)
    from dataclasses import replace

    with pytest.raises(OSError, match="No space left"):
        train(replace(config, steps=15, resume=True))
    after = {p.name: p.read_bytes() for p in folder.iterdir()}
    assert after == before  # no half-written file, the old ones intact


def test_failed_frame_write_leaves_the_dataset_as_it_was(tmp_path, monkeypatch):
    out = tmp_path / "ds"
    config = GenerateConfig(out=out, categories="pen", objects_per_category=2, views=3, width=32, height=24)
    generate_dataset(config, progress=False)
    index = (out / "dataset.json").read_bytes()
    import affnerf.data.writer as writer

    def disk_full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(writer, "write_depth", disk_full)
    from dataclasses import replace

    with pytest.raises(OSError):
        generate_dataset(replace(config, categories="pen,screwdriver"), progress=False)
    assert (out / "dataset.json").read_bytes() == index or {
        o["id"] for o in json.loads((out / "dataset.json").read_text())["objects"]
    } == {"pen_0000", "pen_0001"}
    assert not any((out / ".partial").iterdir())
    assert not (out / "screwdriver").exists() or not any((out / "screwdriver").iterdir())
    with pytest.raises(AffnerfError):  # and the other settings are still refused, so nothing was overwritten
        generate_dataset(replace(config, views=4), progress=False)
