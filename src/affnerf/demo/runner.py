"""``affnerf demo``: predict and grasp on every example image with the shipped model, and report; with
``--train``, the whole pipeline from scratch at a small scale (generate, train, eval, predict, grasp)."""

from __future__ import annotations

import json
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from PIL import Image
from tqdm import tqdm

from affnerf.demo.report import ExampleResult, write_report
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.io import default_clearance, plan_into
from affnerf.grasp.planner import PlanConfig
from affnerf.grasp.size import CATEGORY_SIZE, extent
from affnerf.grasp.target import GraspObject
from affnerf.meshio import read_labelled_ply
from affnerf.pictures.meshes import mesh_preview
from affnerf.pictures.sheets import overview_sheet
from affnerf.predict.outputs import PredictConfig, write_prediction
from affnerf.predict.predictor import Predictor

#: The affordance the demo grasps by, when the predicted model has it.
GRASP_AFFORDANCES = ("grasp", "pull")


def repository_examples() -> Path:
    """The ``examples/`` folder of the checkout (the demo's default inputs)."""
    return Path(__file__).resolve().parents[3] / "examples"


@dataclass(frozen=True)
class DemoConfig:
    """Settings of ``affnerf demo``.

    Attributes:
        out: output folder (the report is OUT/report.html).
        run: the model (default: the shipped one).
        examples: folder of example images (default: the repository's examples/).
        train: run the whole pipeline from scratch at a small scale instead (generate, train, eval, predict, grasp).
        train_minutes: training time of ``--train``.
        views: turntable views per example.
        grasps: grasps planned per example.
        device: ``auto``, ``cpu`` or ``cuda``.
    """

    out: Path = Path("demo_out")
    run: Path | None = None
    examples: Path | None = None
    train: bool = False
    train_minutes: float = 4.0
    views: int = 8
    grasps: int = 16
    device: str = "auto"


def demo_example(predictor: Predictor, image: Path, out: Path, config: DemoConfig) -> ExampleResult:
    """Predict, plan grasps and draw pictures for one example image; files go to ``out``."""
    timing: dict[str, float] = {}
    start = time.perf_counter()
    summary = write_prediction(predictor, PredictConfig(image=image, out=out, views=config.views, device=config.device))
    timing["predict"] = time.perf_counter() - start
    shutil.copyfile(image, out / f"original{image.suffix}")
    mesh_file = out / "affordance_model.ply"
    grasps_info: dict[str, Any] = {}
    grasp_png = None
    if mesh_file.is_file():
        mesh = read_labelled_ply(mesh_file)
        Image.fromarray(mesh_preview(mesh)).save(out / "mesh_preview.png")
        start = time.perf_counter()
        canonical = GraspObject.from_mesh(mesh, str(mesh_file))
        present = set(summary["classes_present"])
        wanted = next((a for a in GRASP_AFFORDANCES if a in present), "none")
        category = image.stem if image.stem in CATEGORY_SIZE else None  # grasps at the category's typical size
        plan = PlanConfig(affordance=wanted, num=config.grasps, width_clearance=default_clearance(mesh_file))
        planned = plan_into(out / "grasps", canonical, mesh_file, plan, ParallelJawGripper(), category=category)
        grasp_png = "grasps/grasps.png" if planned.grasps else None
        grasps_info = {
            "affordance": wanted,
            "count": len(planned.grasps),
            "best_epsilon": max((g.epsilon for g in planned.grasps), default=0.0),
            "largest_side_m": extent(planned.obj.vertices),
            "size_source": planned.size.source,
        }
        timing["grasp"] = time.perf_counter() - start
    else:
        Image.new("RGB", (240, 240), (255, 255, 255)).save(out / "mesh_preview.png")
    rel = out.name
    return ExampleResult(
        name=image.stem,
        input_image=f"{rel}/original{image.suffix}",
        prepared=f"{rel}/input.png",
        turntable=f"{rel}/turntable.gif",
        mesh_preview=f"{rel}/mesh_preview.png",
        grasps_picture=f"{rel}/{grasp_png}" if grasp_png else None,
        model_file=f"{rel}/affordance_model.ply" if mesh_file.is_file() else None,
        classes=summary["surface_area_m2"],
        grasps=grasps_info,
        seconds=timing,
    )


def model_metrics(run: Path) -> dict[str, Any] | None:
    """Evaluation metrics shipped beside a model (``<checkpoint>.metrics.json``) or in its run folder."""
    run = Path(run)
    for candidate in (
        run.with_suffix(".metrics.json"),
        run / "eval" / "metrics.json",
        run.parent / "eval" / "metrics.json",
    ):
        if candidate.is_file():
            return json.loads(candidate.read_text())
    return None


def run_examples(config: DemoConfig, run: Path, examples: Path, metrics: dict[str, Any] | None = None) -> Path:
    """Predict and grasp on every example image and write OUT/report.html."""
    started = time.perf_counter()
    images = sorted(p for p in Path(examples).iterdir() if p.suffix.lower() in (".png", ".jpg", ".jpeg"))
    if not images:
        raise FileNotFoundError(f"{examples}: no example images")
    predictor = Predictor.load(run, config.device)
    out = Path(config.out)
    out.mkdir(parents=True, exist_ok=True)
    results = []
    bar = tqdm(images, desc="examples", unit="image")
    for image in bar:
        bar.set_postfix_str(image.stem)
        folder = out / image.stem
        folder.mkdir(exist_ok=True)
        results.append(demo_example(predictor, image, folder, config))
    bar.close()
    sheet = overview_sheet([out / image.stem for image in images])
    if sheet is not None:
        Image.fromarray(sheet).save(out / "overview.png")
    metrics = metrics if metrics is not None else model_metrics(run)
    return write_report(out / "report.html", results, str(run), metrics, time.perf_counter() - started)
