"""``affnerf eval grasp``: the paper's Table 3 and beyond.

For each test object: plan grasps (a) on its mesh without affordance, the paper's "original model", and (b) on
the affordance model AFF-NeRF predicts from one image, restricted to ``grasp``. Every grasp is then scored on the
ground-truth mesh: Ferrari-Canny epsilon, whether both contacts lie on ground-truth ``grasp`` parts (a grasp on a
screwdriver's shaft or a pair of scissors' blades fails the task however stable it is), and a physics lift test
of the best few.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from affnerf.data.dataset import Dataset, ObjectData
from affnerf.errors import AffnerfError
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.fileio import write_json_atomic
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.planner import PlanConfig, plan_grasps
from affnerf.grasp.scoring import score_grasps
from affnerf.grasp.target import GraspObject
from affnerf.meshio import read_labelled_ply
from affnerf.model.inputs import dataset_views
from affnerf.predict.loading import LoadedModel, load_model
from affnerf.predict.mesh import model_mesh
from affnerf.predict.predictor import pick_device

CONDITIONS = ("original", "affordance")
LABELS = {"original": "Original model (no affordance)", "affordance": "Affordance model"}


@dataclass(frozen=True)
class GraspEvalConfig:
    """Settings of ``affnerf eval grasp``.

    Attributes:
        run: a trained AFF-NeRF run (predicts the affordance models).
        data: the dataset (ground-truth meshes of the test objects).
        out: output folder.
        categories: comma-separated categories.
        split: the split whose objects are grasped.
        num: grasps planned per object and condition.
        lift: run the physics lift test.
        lift_grasps: best grasps per object and condition lifted in physics.
        resolution: marching-cubes resolution of the predicted models.
        level: density level of the predicted surfaces (None: the model config's ``surface_density``).
        max_objects: at most this many objects per category (0 = all).
        refine_steps: local-search steps of the planner.
        seed: seed of the input-view choice and the planner.
        device: ``auto``, ``cpu`` or ``cuda``.
    """

    run: Path
    data: Path
    out: Path
    categories: str = "screwdriver,pen,scissors,eyeglasses"
    split: str = "test"
    num: int = 16
    lift: bool = True
    lift_grasps: int = 5
    resolution: int = 128
    level: float | None = None
    max_objects: int = 0
    refine_steps: int = 20
    seed: int = 0
    device: str = "auto"


def predicted_object(
    loaded: LoadedModel, obj: ObjectData, view: int, resolution: int, level: float | None = None
) -> GraspObject:
    """The affordance model AFF-NeRF predicts from one view of a dataset object, as a graspable mesh."""
    model = loaded.model
    images, intr, poses = dataset_views(obj, [view], model.config.encoder_resolution)
    encoding = model.encode_views(images.to(loaded.device), intr.to(loaded.device), poses.to(loaded.device))
    mesh = model_mesh(model, encoding, resolution, level, model.occupancy(encoding))
    return GraspObject.from_mesh(mesh, f"{obj.record.object_id} (predicted)")


def _lift(gt: GraspObject, grasps: list, count: int) -> list[bool]:
    import trimesh

    from affnerf.grasp.physics import lift_test

    mesh = trimesh.Trimesh(gt.vertices, gt.faces, process=False)
    return [bool(lift_test(mesh, g.pose, g.width).success) for g in grasps[:count]]


def evaluate_object(
    loaded: LoadedModel, obj: ObjectData, config: GraspEvalConfig, gripper: ParallelJawGripper
) -> dict[str, Any]:
    """Both conditions on one object: per condition, epsilon, on-affordance flags and lift results per grasp."""
    gt = GraspObject.from_mesh(read_labelled_ply(obj.folder / "mesh.ply"), obj.record.object_id)
    view = choose_views(
        len(obj), obj.record.object_id, ProtocolConfig(input_views=1, target_views=0, seed=config.seed)
    )[0][0]
    plan = PlanConfig(num=config.num, seed=config.seed)
    plan = replace(plan, refine=replace(plan.refine, steps=config.refine_steps))
    sources = {"original": (GraspObject(gt.vertices, gt.faces, None, gt.name), replace(plan, affordance="none"))}
    predicted = predicted_object(loaded, obj, view, config.resolution, config.level)
    sources["affordance"] = (predicted, replace(plan, affordance="grasp"))
    result: dict[str, Any] = {"object_id": obj.record.object_id, "category": obj.record.category, "input_view": view}
    for condition, (planning_mesh, plan_config) in sources.items():
        try:
            grasps = plan_grasps(planning_mesh, plan_config, gripper) if len(planning_mesh.faces) else []
        except AffnerfError:  # the prediction has no grasp surface: no grasps for this object
            grasps = []
        scores = score_grasps(gt, np.stack([g.pose for g in grasps]) if grasps else np.zeros((0, 4, 4)), gripper)
        result[condition] = {
            "grasps": len(grasps),
            "epsilon": [s.epsilon for s in scores],
            "on_grasp": [s.on("grasp") for s in scores],
            "lift": _lift(gt, grasps, config.lift_grasps) if config.lift and grasps else [],
        }
    return result


def _mean(values: list) -> float | None:
    return float(np.mean(values)) if len(values) else None


def summarise(objects: list[dict[str, Any]]) -> dict[str, Any]:
    """Per category and condition: mean epsilon, on-affordance share, lift success rate, grasps planned; and the
    mean over categories. A condition with no grasp on an object counts its epsilon as 0 for that object."""
    out: dict[str, Any] = {"categories": {}, "mean": {}}
    cats = sorted({o["category"] for o in objects})
    for cat in cats:
        rows = [o for o in objects if o["category"] == cat]
        out["categories"][cat] = {}
        for cond in CONDITIONS:
            eps = [float(np.mean(o[cond]["epsilon"])) if o[cond]["epsilon"] else 0.0 for o in rows]
            on = [x for o in rows for x in o[cond]["on_grasp"]]
            lift = [x for o in rows for x in o[cond]["lift"]]
            out["categories"][cat][cond] = {
                "epsilon": _mean(eps),
                "on_grasp_share": _mean(on),
                "lift_success": _mean(lift),
                "grasps": int(sum(o[cond]["grasps"] for o in rows)),
                "objects": len(rows),
            }
    for cond in CONDITIONS:
        out["mean"][cond] = {}
        for key in ("epsilon", "on_grasp_share", "lift_success"):
            vals = [out["categories"][c][cond][key] for c in cats if out["categories"][c][cond][key] is not None]
            out["mean"][cond][key] = _mean(vals)
    return out


def table3_markdown(summary: dict[str, Any], context: dict[str, Any]) -> str:
    """Markdown laid out like the paper's Table 3 (epsilon, rows = conditions, columns = categories), with the
    on-affordance share and the lift success rate as further tables."""
    cats = sorted(summary["categories"])
    lines = [f"# Grasps on {context.get('split', 'test')} objects, laid out like the paper's Table 3", ""]
    for key, title in (
        ("epsilon", "Ferrari-Canny epsilon (mean over planned grasps, scored on the ground-truth mesh)"),
        ("on_grasp_share", "Share of grasps with both contacts on ground-truth `grasp` parts"),
        ("lift_success", "Physics lift success rate (best grasps per object)"),
    ):
        lines += [f"**{title}**", "", "| | " + " | ".join(cats) + " | Average |", "|" + " --- |" * (len(cats) + 2)]
        for cond in CONDITIONS:
            cells = [summary["categories"][c][cond][key] for c in cats] + [summary["mean"][cond][key]]
            fmt = [("–" if v is None else (f"{v:.4f}" if key == "epsilon" else f"{100 * v:.0f}%")) for v in cells]
            lines.append(f"| {LABELS[cond]} | " + " | ".join(fmt) + " |")
        lines.append("")
    objects = {c: summary["categories"][c]["original"]["objects"] for c in cats}
    lines += [f"Objects per category: {objects}. Settings: `{context}`", ""]
    return "\n".join(lines)


def run_grasp_eval(config: GraspEvalConfig) -> dict[str, Any]:
    """Evaluate every object; write ``grasp_objects.json``, ``grasp_metrics.json`` and ``table3.md``."""
    started = time.perf_counter()
    ds = Dataset.open(config.data)
    loaded = load_model(config.run, pick_device(config.device))
    if loaded.model.config.kind != "affnerf":
        raise AffnerfError(f"{loaded.path}: grasp evaluation predicts affordance models with an AFF-NeRF run")
    cats = [c.strip() for c in config.categories.split(",") if c.strip()]
    entries = ds.objects(config.split, cats)
    if config.max_objects:
        entries = [e for c in cats for e in [x for x in entries if x.category == c][: config.max_objects]]
    if not entries:
        raise AffnerfError(f"{ds.root / 'dataset.json'}: no {config.split} objects of {', '.join(cats)}")
    gripper = ParallelJawGripper()
    objects = [evaluate_object(loaded, ds.load_object(e), config, gripper) for e in entries]
    summary = summarise(objects)
    context = {**{k: str(v) for k, v in asdict(config).items()}, "seconds": round(time.perf_counter() - started, 1)}
    out = Path(config.out)
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "grasp_objects.json", objects)
    write_json_atomic(out / "grasp_metrics.json", {**summary, "settings": context})
    (out / "table3.md").write_text(table3_markdown(summary, context))
    return summary
