"""The viewer's content as plain arrays: the mesh split by affordance class, the grippers at the grasps, and the
input image. Nothing here talks to viser."""

from __future__ import annotations

import json
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import trimesh

from affnerf.errors import input_error
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.meshio import majority_face_labels, read_labelled_ply
from affnerf.vocab import AFFORDANCE_CLASSES, colorize_labels

#: Colour and name of faces labelled 0 (background): grey, so that they stay visible.
UNLABELLED_COLOR, UNLABELLED_NAME = (150, 150, 150), "background"
#: Colour of a mesh without affordance labels and no colours of its own.
PLAIN_COLOR = (190, 190, 190)


@dataclass(frozen=True)
class MeshPart:
    """The faces of one affordance class (or the whole mesh, when it carries no labels).

    Attributes:
        label: the class id, or None for an unlabelled mesh.
        name: the class name (or the file name).
        color: RGB display colour.
        mesh: the faces, with only the vertices they use.
        area: surface area, m^2.
    """

    label: int | None
    name: str
    color: tuple[int, int, int]
    mesh: trimesh.Trimesh
    area: float


@dataclass(frozen=True)
class GraspModel:
    """One grasp of a grasps file, ranked as the file lists them (best first).

    Attributes:
        rank: position in the file, 0 = best.
        pose: (4, 4) grasp frame -> frame of the mesh the grasps were planned on (canonical for predictions).
        width: opening, metres.
        epsilon: Ferrari-Canny epsilon when the file has it.
        affordance: affordance at the contacts when the file has it.
        mesh: the gripper (fingers and palm) in that frame, scaled with it.
    """

    rank: int
    pose: np.ndarray
    width: float
    epsilon: float | None
    affordance: tuple[str, ...]
    mesh: trimesh.Trimesh


def class_name(label: int) -> str:
    """Display name of a class id ("background" for 0, "class N" past the vocabulary)."""
    if label == 0:
        return UNLABELLED_NAME
    return AFFORDANCE_CLASSES[label] if 0 <= label < len(AFFORDANCE_CLASSES) else f"class {label}"


def class_color(label: int) -> tuple[int, int, int]:
    """Display colour of a class id: the affordance palette (grey for background)."""
    if label == 0:
        return UNLABELLED_COLOR
    r, g, b = (int(c) for c in colorize_labels(np.array(label)))
    return r, g, b


def load_mesh(path: Path) -> tuple[trimesh.Trimesh, np.ndarray | None]:
    """The mesh and its per-face affordance ids (None when it has none).

    PLY files are read with :func:`affnerf.meshio.read_labelled_ply`: the face property ``affordance`` is used,
    else the vertex property (each face takes the label most of its vertices carry). Other formats are plain.

    Raises:
        AffnerfError: naming the file when it cannot be read or has no faces.
    """
    path = Path(path)
    if path.suffix.lower() == ".ply":
        labelled = read_labelled_ply(path)
        mesh = labelled.to_trimesh()
        if "affordance" in labelled.face_props:
            return mesh, np.asarray(labelled.face_props["affordance"], np.int64)
        if "affordance" in labelled.vertex_props:
            return mesh, majority_face_labels(labelled.faces, np.asarray(labelled.vertex_props["affordance"], np.int64))
        return mesh, None
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise input_error(path, f"cannot read mesh ({type(exc).__name__}: {exc})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise input_error(path, "mesh has no faces")
    if not np.isfinite(mesh.vertices).all():
        raise input_error(path, "mesh has non-finite vertices")
    return mesh, None


def submesh(mesh: trimesh.Trimesh, face_mask: np.ndarray) -> trimesh.Trimesh:
    """The faces selected by ``face_mask``, re-indexed to the vertices they use."""
    faces = np.asarray(mesh.faces)[face_mask]
    used, inverse = np.unique(faces.reshape(-1), return_inverse=True)
    return trimesh.Trimesh(np.asarray(mesh.vertices)[used], inverse.reshape(-1, 3), process=False)


def split_by_class(mesh: trimesh.Trimesh, face_labels: np.ndarray | None, name: str = "mesh") -> list[MeshPart]:
    """One part per affordance class present (by id), or a single unlabelled part named ``name``."""
    if face_labels is None:
        return [MeshPart(None, name, PLAIN_COLOR, mesh, float(mesh.area))]
    parts = []
    for label in np.unique(face_labels):
        part = submesh(mesh, face_labels == label)
        parts.append(MeshPart(int(label), class_name(int(label)), class_color(int(label)), part, float(part.area)))
    return parts


def load_parts(path: Path) -> list[MeshPart]:
    """The mesh at ``path`` split by affordance class (see :func:`load_mesh`, :func:`split_by_class`)."""
    mesh, labels = load_mesh(path)
    return split_by_class(mesh, labels, Path(path).name)


def _gripper_from(spec: object) -> ParallelJawGripper:
    """The gripper a grasps file describes (its ``gripper`` entry), else the default one."""
    if not isinstance(spec, dict):
        return ParallelJawGripper()
    known = {f.name for f in fields(ParallelJawGripper)}
    sizes = {k: float(v) for k, v in spec.items() if k in known and isinstance(v, (int, float)) and v > 0}
    return ParallelJawGripper(**sizes)


def load_grasps(path: Path) -> list[GraspModel]:
    """The grasps of a ``grasps.json`` with their gripper models, in the file's order (best first), placed in the
    frame of the mesh they were planned on: a file in the metric frame (``size.scale`` given) is brought back to the
    canonical mesh by that scale, gripper included, so it sits where it grasps.

    Raises:
        AffnerfError: naming the file when it is missing, not JSON or not a grasps file.
    """
    from affnerf.grasp.io import read_grasp_scale, read_grasps

    poses = read_grasps(path)
    scale = read_grasp_scale(path) or 1.0
    data = json.loads(Path(path).read_text())
    hand = _gripper_from(data.get("gripper"))
    out = []
    for rank, ((pose, width), entry) in enumerate(zip(poses, data["grasps"], strict=True)):
        mesh = trimesh.util.concatenate(hand.meshes(width))
        mesh.apply_transform(pose)
        mesh.apply_scale(scale)
        pose = pose.copy()
        pose[:3, 3] *= scale
        eps = entry.get("epsilon")
        epsilon = float(eps) if isinstance(eps, (int, float)) else None
        aff = entry.get("affordance")
        affordance = tuple(str(a) for a in aff) if isinstance(aff, list) else ((str(aff),) if aff else ())
        out.append(GraspModel(rank, pose, width, epsilon, affordance, mesh))
    return out


def load_image(path: Path, max_side: int = 512) -> np.ndarray:
    """(H, W, 3) uint8 RGB of an image (transparency over white), shrunk so its longer side is at most
    ``max_side``.

    Raises:
        AffnerfError: naming the file when it cannot be read.
    """
    from PIL import Image

    try:
        with Image.open(path) as im:
            im = im.convert("RGBA")
            im.thumbnail((max_side, max_side))
            canvas = Image.new("RGBA", im.size, (255, 255, 255, 255))
            rgb = Image.alpha_composite(canvas, im).convert("RGB")
    except Exception as exc:  # PIL raises many types for broken files
        raise input_error(path, f"cannot read image ({type(exc).__name__}: {exc})") from None
    return np.asarray(rgb, np.uint8)
