"""What ``affnerf view PATH`` shows, found from PATH: the mesh, the grasps and the input image with its camera.

PATH is a mesh file or a folder: a prediction folder (``affordance_model.ply``, ``input.png``), a dataset object
folder (``mesh.ply``, ``transforms.json``) or a grasps folder (``grasps.json``, whose ``mesh`` entry or parent folder
names the mesh). Nothing here draws; :mod:`affnerf.viewer.server` does.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from affnerf.errors import AffnerfError, input_error

#: Mesh files looked for inside a folder, in this order.
MESH_NAMES = ("affordance_model.ply", "mesh.ply")
#: Mesh formats the viewer reads (PLY with labels; the others as plain meshes).
MESH_SUFFIXES = (".ply", ".glb", ".gltf", ".obj", ".off", ".stl")
#: Where the turntable of ``affnerf predict`` starts (its defaults: 25 degrees up, 0.75 m away).
TURNTABLE_ELEVATION_DEG, TURNTABLE_RADIUS = 25.0, 0.75


@dataclass(frozen=True)
class InputCamera:
    """The camera of the input image.

    Attributes:
        c2w: (4, 4) camera-to-world, OpenGL convention (looks along -z, +y up; conventions §1).
        fov_y: vertical field of view, radians.
        aspect: width / height.
        image: the image file, or None.
        exact: True for a dataset frame's real camera, False for a stand-in (a prediction is pose-free).
        note: one sentence saying where the camera comes from, for the GUI.
    """

    c2w: np.ndarray
    fov_y: float
    aspect: float
    image: Path | None
    exact: bool
    note: str


@dataclass(frozen=True)
class ViewerSources:
    """The files behind one view: the mesh, the grasps file (or None) and the input camera (or None)."""

    mesh: Path
    grasps: Path | None
    camera: InputCamera | None


def find_sources(path: Path) -> ViewerSources:
    """Find the mesh, grasps and input camera for PATH (a mesh file or a folder).

    Raises:
        AffnerfError: naming PATH when it does not exist, is not a mesh, or is a folder without one.
    """
    path = Path(path)
    mesh = find_mesh(path)
    return ViewerSources(mesh, find_grasps(path, mesh), find_camera(mesh.parent))


def find_mesh(path: Path) -> Path:
    """The mesh file PATH names, or the one inside the folder PATH (see the module docstring)."""
    if not path.exists():
        raise input_error(path, "not found")
    if path.is_file():
        if path.suffix.lower() not in MESH_SUFFIXES:
            raise input_error(path, f"not a mesh file (expected one of {', '.join(MESH_SUFFIXES)})")
        return path
    for folder in (path, path.parent) if path.name == "grasps" else (path,):
        for name in MESH_NAMES:
            if (folder / name).is_file():
                return folder / name
    named = _mesh_named_by_grasps(path)
    if named is not None:
        return named
    raise input_error(path, f"no mesh in this folder (looked for {' or '.join(MESH_NAMES)})")


def _mesh_named_by_grasps(folder: Path) -> Path | None:
    """The mesh a ``grasps.json`` in ``folder`` was planned on, when that file still exists."""
    try:
        entry = json.loads((folder / "grasps.json").read_text()).get("mesh")
    except (OSError, ValueError, AttributeError):
        return None
    if not isinstance(entry, str) or not entry:
        return None
    for candidate in (Path(entry), folder / entry):
        if candidate.is_file() and candidate.suffix.lower() in MESH_SUFFIXES:
            return candidate
    return None


def find_grasps(path: Path, mesh: Path) -> Path | None:
    """``grasps.json`` in PATH (a folder) or beside the mesh, or in a ``grasps/`` subfolder of either."""
    folders = [path] if path.is_dir() else []
    folders.append(mesh.parent)
    for folder in folders:
        for candidate in (folder / "grasps.json", folder / "grasps" / "grasps.json"):
            if candidate.is_file():
                return candidate
    return None


def find_camera(folder: Path) -> InputCamera | None:
    """The input camera of a dataset object folder (frame 0) or a prediction folder (a stand-in), else None."""
    if (folder / "transforms.json").is_file():
        return dataset_camera(folder / "transforms.json")
    if (folder / "input.png").is_file():
        return prediction_camera(folder / "input.png")
    return None


def dataset_camera(transforms: Path) -> InputCamera:
    """Frame 0 of a dataset object: its ``transform_matrix``, intrinsics and RGB image.

    Raises:
        AffnerfError: naming ``transforms.json`` when it is unreadable or lacks what is needed.
    """
    from affnerf.data.format import check_pose

    try:
        meta = json.loads(transforms.read_text())
        frame = meta["frames"][0]
        w, h = float(meta["w"]), float(meta["h"])
        fl_y = float(meta.get("fl_y", meta.get("fl_x")))
    except (OSError, ValueError, KeyError, IndexError, TypeError) as exc:
        raise input_error(transforms, f"cannot read frame 0's camera ({type(exc).__name__}: {exc})") from None
    if not (w > 0 and h > 0 and fl_y > 0):
        raise input_error(transforms, "w, h and fl_y must be positive")
    c2w = check_pose(frame.get("transform_matrix"), transforms, "frames[0].transform_matrix")
    image = transforms.parent / str(frame.get("file_path", ""))
    if not image.is_file() and image.with_suffix(".png").is_file():
        image = image.with_suffix(".png")
    note = f"Frame 0's camera and RGB image ({transforms.name})."
    return InputCamera(c2w, 2.0 * math.atan(h / (2.0 * fl_y)), w / h, image if image.is_file() else None, True, note)


def fitted_camera(image: Path) -> InputCamera | None:
    """The camera the fit found for a prediction's ``input.png`` (``fit.camera`` of the ``prediction.json`` beside
    it: its camera-to-canonical pose and the crop's field of view), or None when there is none (``--fit-steps 0``,
    an older prediction, an unreadable file)."""
    from affnerf.predict.outputs import read_fit_camera

    try:
        found = read_fit_camera(image.parent / "prediction.json")
    except AffnerfError:
        return None
    if found is None or found[1] is None or not 0.0 < found[1] < 180.0:
        return None
    note = (
        "The camera the fit to the photo found (prediction.json: fit.camera), drawn with the crop the encoders saw "
        "on its axis (the crop's own offset from the photo's centre is not shown)."
    )
    return InputCamera(found[0], math.radians(found[1]), 1.0, image, False, note)


def prediction_camera(image: Path) -> InputCamera:
    """The camera of a prediction's ``input.png``: the one the fit found (:func:`fitted_camera`), else a stand-in,
    the first turntable camera (from -y, 25 degrees up, 0.75 m away) with the training cameras' 60 degree
    horizontal field of view."""
    fitted = fitted_camera(image)
    if fitted is not None:
        return fitted
    from PIL import Image

    from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X
    from affnerf.predict.predictor import turntable_poses

    try:
        with Image.open(image) as im:
            w, h = im.size
    except Exception as exc:  # PIL raises many types for broken files
        raise input_error(image, f"cannot read image ({type(exc).__name__}: {exc})") from None
    aspect = w / h
    fov_y = 2.0 * math.atan(math.tan(DEFAULT_CAMERA_ANGLE_X / 2.0) / aspect)
    pose = turntable_poses(1, TURNTABLE_ELEVATION_DEG, TURNTABLE_RADIUS)[0]
    note = (
        "Approximate camera: the prediction is pose-free, so the input image is drawn at the first turntable "
        f"camera (from -y, {TURNTABLE_ELEVATION_DEG:g} degrees up, {TURNTABLE_RADIUS:g} m away)."
    )
    return InputCamera(np.asarray(pose, np.float64), fov_y, aspect, image, False, note)
