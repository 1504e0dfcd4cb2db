"""``affnerf demo --train``: the whole pipeline from scratch at a small scale, timed stage by stage."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from PIL import Image

from affnerf.data.dataset import Dataset
from affnerf.data.generate import GenerateConfig, generate_dataset
from affnerf.demo.runner import DemoConfig, run_examples
from affnerf.eval.runner import EvalConfig, run_eval
from affnerf.train.config import SMALL
from affnerf.train.trainer import train


def _train_small(data: Path, run: Path, config: DemoConfig) -> None:
    """The small configuration for ``config.train_minutes`` (resuming a run folder left by an earlier demo)."""
    resume = (run / "checkpoints").is_dir()
    train(replace(SMALL, data=data, out=run, steps=10**6, time_limit=config.train_minutes, val_every=0,
                  resume=resume, device=config.device))  # fmt: skip


def _evaluate_small(data: Path, run: Path, out: Path, config: DemoConfig) -> dict[str, Any]:
    """AFF-NeRF, retrieval and the constant floor on the test split: 4 targets at half size, meshes at 64^3."""
    eval_config = EvalConfig(run=run, data=data, out=out, method="affnerf,retrieval,constant", target_views=4,
                             scale=0.5, mesh_resolution=64, device=config.device)  # fmt: skip
    return run_eval(eval_config)


def run_pipeline(config: DemoConfig) -> dict[str, Any]:
    """Generate a small dataset, train the small configuration, evaluate, predict and grasp; returns the stage
    timings (seconds) and where everything went."""
    out = Path(config.out)
    stages: dict[str, float] = {}

    def stage(name: str, start: float) -> None:
        stages[name] = round(time.perf_counter() - start, 1)
        print(f"[{name}] {stages[name]:.1f} s", flush=True)

    t = time.perf_counter()
    data, run = out / "dataset", out / "run"
    generate_dataset(GenerateConfig(out=data, objects_per_category=3, views=24, width=200, height=150, workers=2))
    stage("generate", t)
    t = time.perf_counter()
    _train_small(data, run, config)
    stage("train", t)
    t = time.perf_counter()
    evaluation = _evaluate_small(data, run, out / "eval", config)
    stage("eval", t)
    t = time.perf_counter()
    examples = out / "examples"
    examples.mkdir(parents=True, exist_ok=True)
    ds = Dataset.open(data)
    for entry in ds.objects(split="test"):
        Image.fromarray(ds.load_object(entry).rgb(0)).save(examples / f"{entry.id}.png")
    report = run_examples(replace(config, out=out / "predictions"), run, examples, evaluation.get("affnerf"))
    stage("predict + grasp", t)
    summary = {
        "stages_seconds": stages,
        "report": str(report),
        "dataset": str(data),
        "run": str(run),
        "eval": str(out / "eval" / "table2.md"),
    }
    (out / "pipeline.json").write_text(json.dumps(summary, indent=1))
    return summary
