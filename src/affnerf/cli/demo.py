"""``affnerf demo``: the main job on a fresh machine."""

from __future__ import annotations

from typing import Annotated

import tyro

from affnerf.demo.runner import DemoConfig


def demo(config: Annotated[DemoConfig, tyro.conf.arg(name="")]) -> None:
    """Predict a 3D affordance model and plan grasps for every example image with the shipped model, and write
    OUT/report.html (inputs, turntables, labelled meshes, grasps, the model's metrics).

    With --train, run the whole pipeline from scratch at a small scale instead (generate a dataset, train the small
    configuration, evaluate, predict, grasp) and print how long each stage took.
    """
    from affnerf.demo.runner import repository_examples, run_examples
    from affnerf.predict.shipped import shipped_model

    if config.train:
        from affnerf.demo.pipeline import run_pipeline

        summary = run_pipeline(config)
        print("stages:", ", ".join(f"{k} {v:.0f} s" for k, v in summary["stages_seconds"].items()))
        print(f"report: {summary['report']}")
        return
    run = config.run if config.run is not None else shipped_model()
    examples = config.examples if config.examples is not None else repository_examples()
    report = run_examples(config, run, examples)
    print(f"report: {report.resolve()}")
