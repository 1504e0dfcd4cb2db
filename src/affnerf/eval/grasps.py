"""``affnerf eval grasp``: the paper's Table 3 (conventions §6).

For each object, grasps are planned on {its true mesh, the affordance model AFF-NeRF predicts from one image} ×
{the whole surface, the task's affordance only (``grasp``; cabinet: ``pull``)}, and on the true mesh restricted to
the task part of the labels the predicted field gives its faces (the predicted affordance without the predicted
shape's error). Every grasp is then scored on the true mesh at the object's metric size (canonical / ``scale`` of
its ``transforms.json``, or ``--object-size``): Ferrari-Canny epsilon, whether both contacts lie on the true task
part (a grasp on a screwdriver's shaft fails the task however stable it is), and a physics lift test of the best
few, then a disturbance (a turn about the closing axis and a shake) of those lifted. The predicted model is
brought to metric size by the same factor as the true mesh. The table itself is :mod:`affnerf.eval.grasp_table`.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from tqdm import tqdm

from affnerf.data.dataset import Dataset, IndexEntry, ObjectData
from affnerf.data.pool import run_jobs
from affnerf.environment import describe_machine
from affnerf.errors import AffnerfError
from affnerf.eval.grasp_intervals import table3_summary
from affnerf.eval.grasp_table import CONDITIONS, mesh_of, summarise, table3_markdown, task_affordance, whole_of
from affnerf.eval.protocol import ProtocolConfig, choose_views
from affnerf.fileio import write_json_atomic
from affnerf.grasp.explain import explain_no_grasps
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.planner import (
    MIN_CONFIDENCE,
    PART_MARGIN,
    PREDICTED_CLEARANCE,
    RANK,
    Grasp,
    PlanConfig,
    plan_grasps,
)
from affnerf.grasp.scoring import score_grasps
from affnerf.grasp.size import ObjectSize, extent, object_mass, scaled, size_for
from affnerf.grasp.target import GraspObject
from affnerf.meshio import read_labelled_ply
from affnerf.model.inputs import dataset_views
from affnerf.predict.agreement import AGREEMENT_DISTANCE, confirmed
from affnerf.predict.invert import InversionConfig, dataset_crop_target, invert
from affnerf.predict.loading import LoadedModel, load_model
from affnerf.predict.mesh import label_faces, model_mesh
from affnerf.predict.predictor import pick_device

__all__ = ["CONDITIONS", "GraspEvalConfig", "evaluate_object", "run_grasp_eval", "summarise", "table3_markdown"]

DEFAULT_CATEGORIES = "screwdriver,pen,scissors,eyeglasses,bottle,teapot,bucket,cabinet"


@dataclass(frozen=True)
class GraspEvalConfig:
    """Settings of ``affnerf eval grasp``.

    Attributes:
        run: a trained AFF-NeRF run (predicts the affordance models).
        data: the dataset (ground-truth meshes of the test objects).
        out: output folder.
        categories: comma-separated categories (the paper's four, then bottle, teapot, bucket and cabinet).
        split: the split whose objects are grasped.
        num: grasps planned per object and condition.
        lift: run the physics lift test.
        lift_grasps: best grasps per object and condition lifted in physics.
        disturb: after each successful lift, turn the object ±90° about the closing axis and shake it
            (:mod:`affnerf.grasp.disturb`).
        resolution: marching-cubes resolution of the predicted models.
        level: density level of the predicted surfaces (None: the model config's ``surface_density``).
        max_objects: at most this many objects per category (0 = all).
        refine_steps: local-search steps of the planner.
        seed: seed of the input-view choice and the planner.
        device: ``auto``, ``cpu`` or ``cuda``.
        object_size: every object's largest side in metres (None: each object's own, from its ``scale``).
        pictures: write OUT/grasps_<category>.png: the first object's planning meshes, one per condition, with
            their best grasps.
        part_margin: in the task-part conditions, contacts keep this distance (metres, at metric size) from the
            surface of other labels (:class:`~affnerf.grasp.planner.PlanConfig`).
        fit_steps: steps of test-time inversion of the predicted models to their input view (as ``affnerf
            predict``; :mod:`affnerf.predict.invert`); 0 = the encoder's codes.
        agreement_distance: with ``fit_steps``, the task part is planned first on the faces the encoder's own
            prediction confirms (same label within this distance, canonical frame;
            :func:`~affnerf.predict.agreement.agreeing_faces`); 0 = off.
        predicted_clearance: on the predicted models, grasps stay this far (metres) below the gripper's opening
            (:class:`~affnerf.grasp.planner.PlanConfig` ``width_clearance``; a true mesh keeps the planner's
            default), because a section the model makes too narrow may not fit the gripper on the true object
            (1.2 cm, chosen on validation objects: benchmarks/results/grasp_clearance.md).
        min_confidence: in the task-part conditions on the predicted models, contacts are first sought on the
            faces of the part whose label the field gives at least this probability (and that the encoder's own
            prediction confirms); then on the whole part (:class:`~affnerf.grasp.planner.PlanConfig`; 0 = off, the
            default: on validation objects 0.7-0.9 raised the on-part share by 0-2 points and cost lift-and-disturb
            8-13 points, benchmarks/results/grasp_confidence.md).
        rank: what orders every condition's grasps (:class:`~affnerf.grasp.planner.PlanConfig`): ``epsilon``
            (Ferrari-Canny) or ``hold`` (the weight carried while the object turns about the closing axis).
        workers: objects evaluated at once, each in a process of its own on one core and one thread
            (:mod:`affnerf.data.pool`), so that the numbers do not depend on this or on the machine's core count.
    """

    run: Path
    data: Path
    out: Path
    categories: str = DEFAULT_CATEGORIES
    split: str = "test"
    num: int = 16
    lift: bool = True
    lift_grasps: int = 5
    disturb: bool = True
    resolution: int = 128
    level: float | None = None
    max_objects: int = 0
    refine_steps: int = 20
    seed: int = 0
    device: str = "auto"
    object_size: float | None = None
    pictures: bool = True
    part_margin: float = PART_MARGIN
    fit_steps: int = 30
    agreement_distance: float = AGREEMENT_DISTANCE
    predicted_clearance: float = PREDICTED_CLEARANCE
    min_confidence: float = MIN_CONFIDENCE
    rank: Literal["epsilon", "hold"] = RANK
    workers: int = 2


@dataclass(frozen=True)
class Prediction:
    """One object's affordance model predicted from one view.

    Attributes:
        model: the model that predicted it.
        first: the encoder's codes of the view.
        encoding: the codes used (fitted to the view, or ``first``).
        fitted: whether ``encoding`` was fitted to the view.
    """

    model: Any
    first: Any
    encoding: Any
    fitted: bool


def predict_object(loaded: LoadedModel, obj: ObjectData, view: int, fit_steps: int = 0) -> Prediction:
    """Encode one view of a dataset object, then (``fit_steps`` > 0) fit the codes to it for that many steps of
    test-time inversion, as ``affnerf predict`` does."""
    model = loaded.model
    images, intr, poses = dataset_views(obj, [view], model.config)
    first = model.encode_views(images.to(loaded.device), intr.to(loaded.device), poses.to(loaded.device))
    if fit_steps <= 0:
        return Prediction(model, first, first, False)
    target = dataset_crop_target(obj, view, model.config.encoder_resolution)
    config = InversionConfig(steps=fit_steps, seed=view)
    return Prediction(model, first, invert(model, first, target, np.asarray(loaded.background), config).codes, True)


def predicted_object(
    prediction: Prediction, name: str, resolution: int, level: float | None = None, agreement_distance: float = 0.0
) -> GraspObject:
    """The predicted affordance model as a graspable mesh (canonical frame). For fitted codes and
    ``agreement_distance`` > 0, its faces carry ``confirmed`` (:func:`affnerf.predict.agreement.confirmed` against
    the encoder's codes' own mesh), read as the object's ``face_agrees``."""
    model, encoding = prediction.model, prediction.encoding
    mesh = model_mesh(model, encoding, resolution, level, model.occupancy(encoding))
    if prediction.fitted and agreement_distance > 0:
        first = prediction.first
        mesh = confirmed(mesh, model_mesh(model, first, resolution, level, model.occupancy(first)), agreement_distance)
    return GraspObject.from_mesh(mesh, f"{name} (predicted)")


def with_predicted_labels(prediction: Prediction, mesh: GraspObject, agreement: bool = True) -> GraspObject:
    """``mesh`` (the true one, canonical frame) with its faces labelled by the predicted field at their centres
    (:func:`affnerf.predict.mesh.label_faces`): the predicted affordance on the true geometry. For fitted codes
    and ``agreement``, ``face_agrees`` marks the faces where the encoder's own field gives the same label (the
    planner tries those first, as on the predicted mesh)."""
    labels = label_faces(mesh.vertices, mesh.faces, prediction.model.point_fields(prediction.encoding)[1])
    agrees = None
    if prediction.fitted and agreement:
        agrees = label_faces(mesh.vertices, mesh.faces, prediction.model.point_fields(prediction.first)[1]) == labels
    return GraspObject(mesh.vertices, mesh.faces, labels, f"{mesh.name} (predicted labels)", agrees)


def object_size(obj: ObjectData, canonical: GraspObject, config: GraspEvalConfig) -> ObjectSize:
    """How the object's canonical meshes become metric: ``config.object_size``, else its ``scale``."""
    scale = obj.record.extra.get("scale")
    scale = float(scale) if isinstance(scale, (int, float)) and scale > 0 else None
    return size_for(extent(canonical.vertices), config.object_size, scale, obj.record.category)


def _lift(gt: GraspObject, grasps: list[Grasp], count: int, mass: float, disturb: bool) -> tuple[list, list]:
    """Lift-test success of the ``count`` best grasps on the true metric mesh ``gt`` weighing ``mass``, and (when
    ``disturb``) whether each is still held after the disturbance (False after a failed lift; else empty)."""
    import trimesh

    from affnerf.grasp.disturb import lift_and_disturb
    from affnerf.grasp.physics import LiftConfig, lift_test

    mesh = trimesh.Trimesh(gt.vertices, gt.faces, process=False)
    config = LiftConfig(mass=mass)
    if not disturb:
        return [bool(lift_test(mesh, g.pose, g.width, config=config).success) for g in grasps[:count]], []
    results = [lift_and_disturb(mesh, g.pose, g.width, config=config) for g in grasps[:count]]
    return [bool(lift.success) for lift, _ in results], [bool(d is not None and d.held) for _, d in results]


def _plan(
    mesh: GraspObject, config: PlanConfig, gripper: ParallelJawGripper, size_source: str
) -> tuple[list[Grasp], str | None]:
    """Grasps planned on ``mesh``, and why there are none (None when there are some): for a surface the planner
    found nothing on, the narrowest width of the allowed surface against the gripper's opening
    (:func:`~affnerf.grasp.explain.explain_no_grasps`)."""
    if not len(mesh.faces):
        return [], "no predicted surface"
    try:
        grasps = plan_grasps(mesh, config, gripper)
    except AffnerfError as e:  # e.g. the prediction has no surface of the task's affordance
        return [], str(e)
    if grasps:
        return grasps, None
    return [], f"no grasp found: {explain_no_grasps(mesh, config, gripper, size_source)['reason']}"


def _condition(
    gt: GraspObject,
    planning: GraspObject,
    plan: PlanConfig,
    task: str,
    mass: float,
    config: GraspEvalConfig,
    size_source: str = "mesh as given",
) -> tuple[list[Grasp], dict[str, Any]]:
    """Plan on ``planning``, score every grasp on ``gt`` (both metric), lift the best few."""
    gripper = ParallelJawGripper()
    grasps, why = _plan(planning, plan, gripper, size_source)
    scores = score_grasps(gt, np.stack([g.pose for g in grasps]) if grasps else np.zeros((0, 4, 4)), gripper)
    lift, disturb = _lift(gt, grasps, config.lift_grasps, mass, config.disturb) if config.lift else ([], [])
    return grasps, {
        "grasps": len(grasps),
        "no_grasp": why,
        "epsilon": [s.epsilon for s in scores],
        "on_part": [s.on(task) for s in scores],
        "lift": lift,
        "disturb": disturb,
    }


def condition_settings(plan: PlanConfig, mesh: str, affordance: str, config: GraspEvalConfig) -> PlanConfig:
    """The planner's settings for one condition: ``plan`` restricted to ``affordance`` (``none`` = the whole
    surface), with ``config.predicted_clearance`` as the width clearance when ``mesh`` is ``predicted``."""
    settings = replace(plan, affordance=affordance)
    return replace(settings, width_clearance=config.predicted_clearance) if mesh == "predicted" else settings


def planning_meshes(
    canonical: GraspObject, prediction: Prediction, factor: float, config: GraspEvalConfig
) -> dict[str, GraspObject]:
    """Each condition's labelled metric mesh (:data:`CONDITIONS`): the true mesh with its true labels, the true
    mesh labelled by the predicted field (``true_predictedpart``), and the predicted mesh."""
    true = scaled(canonical, factor)
    relabelled = scaled(with_predicted_labels(prediction, canonical, config.agreement_distance > 0), factor)
    predicted = scaled(
        predicted_object(prediction, canonical.name, config.resolution, config.level, config.agreement_distance),
        factor,
    )
    meshes = {"true": true, "predicted": predicted}
    return {cond: relabelled if cond == "true_predictedpart" else meshes[mesh_of(cond)] for cond in CONDITIONS}


def evaluate_object(
    loaded: LoadedModel, obj: ObjectData, config: GraspEvalConfig, picture: Path | None = None
) -> dict[str, Any]:
    """Every condition on one object (:data:`CONDITIONS`): per condition, epsilon, on-task-part flags and
    lift results per grasp, all on the true mesh at metric size; and the size and mass used. With ``picture``,
    also a PNG there of each condition's planning mesh with its best grasps."""
    canonical = GraspObject.from_mesh(read_labelled_ply(obj.folder / "mesh.ply"), obj.record.object_id)
    size = object_size(obj, canonical, config)
    view = choose_views(
        len(obj), obj.record.object_id, ProtocolConfig(input_views=1, target_views=0, seed=config.seed)
    )[0][0]
    meshes = planning_meshes(canonical, predict_object(loaded, obj, view, config.fit_steps), size.factor, config)
    gt = meshes["true_whole"]
    task, mass = task_affordance(obj.record.category), object_mass(gt.vertices, gt.faces, obj.record.category)
    plan = PlanConfig(
        num=config.num,
        seed=config.seed,
        part_margin=config.part_margin,
        min_confidence=config.min_confidence,
        rank=config.rank,
    )
    plan = replace(plan, refine=replace(plan.refine, steps=config.refine_steps))
    result: dict[str, Any] = {
        "object_id": obj.record.object_id,
        "category": obj.record.category,
        "input_view": view,
        "task": task,
        "size": size.to_json(extent(canonical.vertices)),
        "mass": round(mass, 4),
    }
    panels = {}
    for cond, mesh in meshes.items():
        whole = cond == whole_of(cond)
        planning = GraspObject(mesh.vertices, mesh.faces, None, mesh.name) if whole else mesh
        settings = condition_settings(plan, mesh_of(cond), "none" if whole else task, config)
        grasps, result[cond] = _condition(gt, planning, settings, task, mass, config, size.source)
        panels[cond] = (mesh, grasps)
    if picture is not None:
        from affnerf.eval.grasp_pictures import write_category_picture

        write_category_picture(picture, panels)
    return result


@functools.cache
def _worker_inputs(run: Path, data: Path, device: str) -> tuple[LoadedModel, Dataset]:
    """The model and dataset of a worker process, loaded once per process."""
    return load_model(run, pick_device(device)), Dataset.open(data)


def _evaluate_job(config: GraspEvalConfig, job: tuple[IndexEntry, Path | None], done: Callable[[], None]) -> dict:
    """One object of :func:`run_grasp_eval` in a worker process (:func:`affnerf.data.pool.run_jobs`): ``job`` is
    its index entry and the path of its category's picture (None: no picture)."""
    entry, picture = job
    loaded, ds = _worker_inputs(Path(config.run), Path(config.data), config.device)
    result = evaluate_object(loaded, ds.load_object(entry), config, picture)
    done()
    return result


def grasp_entries(ds: Dataset, config: GraspEvalConfig) -> list[IndexEntry]:
    """The objects Table 3 grasps: ``config.split``'s objects of ``config.categories``, in that order, at most
    ``config.max_objects`` per category."""
    cats = [c.strip() for c in config.categories.split(",") if c.strip()]
    entries = ds.objects(config.split, cats)
    if config.max_objects:
        entries = [e for c in cats for e in [x for x in entries if x.category == c][: config.max_objects]]
    if not entries:
        raise AffnerfError(f"{ds.root / 'dataset.json'}: no {config.split} objects of {', '.join(cats)}")
    return entries


def run_grasp_eval(config: GraspEvalConfig) -> dict[str, Any]:
    """Evaluate every object (``config.workers`` at once); write ``grasp_objects.json``, ``grasp_metrics.json``,
    ``table3.md`` and (with ``pictures``) ``grasps_<category>.png`` of each category's first object."""
    started = time.perf_counter()
    if config.workers < 1:
        raise AffnerfError("--workers must be at least 1")
    # the workers load their own model; this one refuses a wrong run in one line before any of them starts
    loaded = load_model(config.run, pick_device(config.device))
    if loaded.model.needs_input_pose:
        raise AffnerfError(
            f"{loaded.path}: grasp evaluation predicts affordance models from one unposed image: "
            f"use an AFF-NeRF (or pose-aware) run, not {loaded.model.config.kind}"
        )
    entries = grasp_entries(Dataset.open(config.data), config)
    out = Path(config.out)
    out.mkdir(parents=True, exist_ok=True)
    firsts = {e.category: e.id for e in reversed(entries)}  # the first object of each category
    pictures = [
        out / f"grasps_{e.category}.png" if config.pictures and firsts[e.category] == e.id else None for e in entries
    ]
    with tqdm(total=len(entries), desc="grasp objects", unit="obj", disable=None) as bar:
        jobs = list(zip(entries, pictures, strict=True))
        done = run_jobs(functools.partial(_evaluate_job, config), jobs, min(config.workers, len(jobs)), bar.update)
        by_id = {o["object_id"]: o for o in done}
    objects = [by_id[e.id] for e in entries]
    summary = table3_summary(objects)
    context = {**{k: str(v) for k, v in asdict(config).items()}, "seconds": round(time.perf_counter() - started, 1)}
    context["machine"] = describe_machine() | {"threads_per_object": 1}
    write_json_atomic(out / "grasp_objects.json", objects)
    write_json_atomic(out / "grasp_metrics.json", {**summary, "settings": context})
    (out / "table3.md").write_text(table3_markdown(summary, context))
    return summary
