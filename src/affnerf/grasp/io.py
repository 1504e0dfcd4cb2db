"""Grasp files and pictures: ``grasps.json`` (written and validated), a GLB scene with the gripper at the best
grasps, and a PNG rendering of them."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from PIL import Image

from affnerf.data.format import check_pose
from affnerf.errors import input_error
from affnerf.fileio import read_json_file, write_json_atomic
from affnerf.grasp.camera_frame import camera_record
from affnerf.grasp.explain import explain_no_grasps
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.planner import PREDICTED_CLEARANCE, WIDTH_CLEARANCE, Grasp, PlanConfig, plan_grasps
from affnerf.grasp.size import ObjectSize, extent, resolve_size, scaled
from affnerf.grasp.target import GraspObject
from affnerf.pictures.meshes import affordance_colors, coloured_surface, views_around
from affnerf.vocab import colorize_labels

FORMAT = "affnerf-grasps-2"
#: Gripper colours in pictures: the best grasp green, the others from yellow to red by rank.
_BEST, _OTHER = (0.1, 0.75, 0.2), (0.95, 0.6, 0.1)


def write_grasps(
    path: Path,
    grasps: list[Grasp],
    mesh: str,
    affordance: str,
    gripper: ParallelJawGripper,
    size: dict[str, Any] | None = None,
    no_grasp: dict[str, Any] | None = None,
    camera: dict[str, Any] | None = None,
) -> None:
    """Write ``grasps.json`` (conventions §6): poses in the metric object frame (canonical × 1 / ``size["scale"]``),
    ``size`` as :meth:`affnerf.grasp.size.ObjectSize.to_json`, why there is no grasp when there is none, and the
    grasps in the photo's camera frame when the mesh is a prediction fitted to its photo
    (:func:`affnerf.grasp.camera_frame.camera_record`)."""
    write_json_atomic(
        path,
        {
            "format": FORMAT,
            "mesh": mesh,
            "affordance": affordance,
            "frame": "metric",
            "size": size or {"scale": 1.0, "largest_side": None, "source": "mesh as given"},
            "gripper": {"type": "parallel", **gripper.__dict__},
            "grasps": [g.to_json() for g in grasps],
            "no_grasp": no_grasp,
            "camera": camera,
        },
    )


def read_grasp_scale(path: Path) -> float | None:
    """``size.scale`` of a grasps file (canonical = pose frame × scale), None when it has none (older files,
    whose poses are in the coordinates of the mesh they were planned on)."""
    data = read_json_file(Path(path))
    scale = data.get("size", {}).get("scale") if isinstance(data, dict) and isinstance(data.get("size"), dict) else None
    if scale is None:
        return None
    if not isinstance(scale, (int, float)) or not np.isfinite(scale) or scale <= 0:
        raise input_error(path, f"size.scale must be a positive number, got {scale!r}")
    return float(scale)


def read_grasps(path: Path) -> list[tuple[np.ndarray, float]]:
    """(pose (4, 4), width) of every grasp in a grasps file.

    Raises:
        AffnerfError: naming the file, for a missing file, invalid JSON or a wrong schema.
    """
    path = Path(path)
    data = read_json_file(path)
    if not isinstance(data, dict) or not isinstance(data.get("grasps"), list):
        raise input_error(path, "expected {'grasps': [{'pose': 4x4, 'width': metres}, ...]}")
    out = []
    for i, g in enumerate(data["grasps"]):
        if not isinstance(g, dict) or "pose" not in g or "width" not in g:
            raise input_error(path, f"grasp {i} needs 'pose' and 'width'")
        pose = check_pose(g["pose"], path, f"grasp {i} pose")
        width = g["width"]
        if not isinstance(width, (int, float)) or not np.isfinite(width) or width < 0:
            raise input_error(path, f"grasp {i} width must be a non-negative number, got {width!r}")
        out.append((pose, float(width)))
    return out


def gripper_meshes(grasps: list[Grasp], gripper: ParallelJawGripper) -> list[trimesh.Trimesh]:
    """One merged gripper mesh per grasp, placed in the object frame."""
    out = []
    for g in grasps:
        parts = gripper.meshes(g.width)
        mesh = trimesh.util.concatenate(parts)
        mesh.apply_transform(g.pose)
        out.append(mesh)
    return out


def object_mesh(obj: GraspObject) -> trimesh.Trimesh:
    """The object coloured by affordance (grey when unlabelled)."""
    mesh = trimesh.Trimesh(obj.vertices, obj.faces, process=False)
    if obj.face_affordance is not None:
        mesh.visual.face_colors = np.concatenate(
            [colorize_labels(obj.face_affordance), np.full((len(obj.faces), 1), 255)], 1
        )
    else:
        mesh.visual.face_colors = [180, 180, 180, 255]
    return mesh


def export_scene(
    path: Path, obj: GraspObject, grasps: list[Grasp], gripper: ParallelJawGripper, count: int = 5
) -> None:
    """A GLB scene: the object and gripper models at the ``count`` best grasps."""
    scene = trimesh.Scene()
    scene.add_geometry(object_mesh(obj), geom_name="object")
    for rank, mesh in enumerate(gripper_meshes(grasps[:count], gripper)):
        mesh.visual.face_colors = [int(255 * c) for c in (_BEST if rank == 0 else _OTHER)] + [255]
        scene.add_geometry(mesh, geom_name=f"grasp_{rank}")
    Path(path).write_bytes(scene.export(file_type="glb"))


def render_grasps(
    obj: GraspObject, grasps: list[Grasp], gripper: ParallelJawGripper, count: int = 3, size: int = 320
) -> np.ndarray:
    """(size, 3 * size, 3) uint8 pictures of the object (coloured by affordance) with the ``count`` best grasps
    (the best green, the others orange), from three sides."""
    labels = obj.face_affordance if obj.face_affordance is not None else np.zeros(len(obj.faces), np.int64)
    vertices, faces, colors = [obj.vertices], [obj.faces], [affordance_colors(labels, 0.6, 0.35)]
    offset = len(obj.vertices)
    for rank, mesh in enumerate(gripper_meshes(grasps[:count], gripper)):
        vertices.append(mesh.vertices)
        faces.append(mesh.faces + offset)
        colors.append(np.tile(_BEST if rank == 0 else _OTHER, (len(mesh.faces), 1)))
        offset += len(mesh.vertices)
    surface = coloured_surface(np.concatenate(vertices), np.concatenate(faces), np.concatenate(colors))
    reach = float(np.ptp(obj.vertices, axis=0).max()) * 1.6 + 0.1
    return views_around(surface, obj.vertices.mean(0), reach, (-90.0, 0.0, 60.0), size, lift=0.6)


def save_png(path: Path, image: np.ndarray) -> None:
    Image.fromarray(image).save(path)


def summary(grasps: list[Grasp]) -> dict[str, Any]:
    """Counts and the quality of the grasps, for printing."""
    eps = [g.epsilon for g in grasps]
    return {
        "grasps": len(grasps),
        "best_epsilon": max(eps, default=0.0),
        "mean_epsilon": float(np.mean(eps)) if eps else 0.0,
    }


@dataclass
class PlannedGrasps:
    """Grasps planned on an object at its metric size.

    Attributes:
        grasps: best first, poses in the metric object frame.
        obj: the object they were planned on (metric).
        size: how the canonical mesh became metric.
        no_grasp: why there is no grasp (:func:`affnerf.grasp.explain.explain_no_grasps`), or None.
    """

    grasps: list[Grasp]
    obj: GraspObject
    size: ObjectSize
    no_grasp: dict[str, Any] | None


def default_clearance(mesh: Path) -> float:
    """The width clearance to plan on ``mesh`` with: the predicted one for a mesh ``affnerf predict`` wrote (a
    ``prediction.json`` beside it), the planner's default otherwise."""
    return PREDICTED_CLEARANCE if (Path(mesh).parent / "prediction.json").is_file() else WIDTH_CLEARANCE


def plan_into(
    out: Path,
    canonical: GraspObject,
    mesh: Path,
    config: PlanConfig,
    gripper: ParallelJawGripper,
    object_size: float | None = None,
    category: str | None = None,
) -> PlannedGrasps:
    """Plan grasps on a canonical mesh (read from ``mesh``) at its metric size (:func:`affnerf.grasp.size.
    resolve_size`) and write OUT/grasps.json, OUT/grasps.glb and OUT/grasps.png; returns what was planned."""
    size = resolve_size(mesh, canonical.vertices, object_size, category)
    obj = scaled(canonical, size.factor)
    grasps = plan_grasps(obj, config, gripper)
    why = None if grasps else explain_no_grasps(obj, config, gripper, size.source)
    out.mkdir(parents=True, exist_ok=True)
    size_json = size.to_json(extent(canonical.vertices))
    poses = np.array([g.pose for g in grasps]).reshape(-1, 4, 4)
    camera = camera_record(mesh, poses, size.factor)
    write_grasps(out / "grasps.json", grasps, str(mesh), config.affordance, gripper, size_json, why, camera)
    export_scene(out / "grasps.glb", obj, grasps, gripper)
    save_png(out / "grasps.png", render_grasps(obj, grasps, gripper))
    return PlannedGrasps(grasps, obj, size, why)
