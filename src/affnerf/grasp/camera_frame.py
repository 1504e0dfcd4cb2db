"""Grasps in the photo's camera frame: what a robot with the camera needs, not the object's canonical frame.

``affnerf predict`` records the camera its fit to the photo found, as a camera-to-canonical pose
(``prediction.json``: ``fit.camera.c2w``, OpenGL convention: x right, y up, the camera looking along -z;
conventions §1, §8). At the object's metric size (canonical metres × ``factor``) that camera sits ``factor``
times farther away, so the object-to-camera transform of the metric object frame is the inverse of the pose with
its translation scaled. Grasp poses in the metric object frame are then moved into the camera frame by it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from affnerf.predict.outputs import read_fit_camera


def fitted_camera_pose(mesh: Path) -> np.ndarray | None:
    """(4, 4) camera-to-canonical pose of the photo a predicted mesh came from (:func:`affnerf.predict.outputs.
    read_fit_camera` of the ``prediction.json`` beside ``mesh``); None without one or without a fit.

    Raises:
        AffnerfError: naming ``prediction.json`` when it is unreadable or its pose is not a rigid 4x4.
    """
    found = read_fit_camera(Path(mesh).parent / "prediction.json")
    return None if found is None else found[0]


def object_to_camera(c2w: np.ndarray, factor: float) -> np.ndarray:
    """(4, 4) transform from the metric object frame (canonical × ``factor``) to the camera frame of a canonical
    camera-to-world pose ``c2w``.

    Example:
        >>> c2w = np.eye(4); c2w[:3, 3] = [0.0, 0.0, 0.5]  # 0.5 canonical metres up +z, looking down -z
        >>> object_to_camera(c2w, 2.0)[:3, 3].tolist()  # the object's origin, 1 m in front of the camera
        [0.0, 0.0, -1.0]
    """
    metric = np.array(c2w, np.float64)
    metric[:3, 3] *= factor
    return np.linalg.inv(metric)


def camera_record(mesh: Path, poses: np.ndarray, factor: float) -> dict | None:
    """The ``camera`` entry of ``grasps.json`` for grasps (G, 4, 4) planned on ``mesh`` at ``factor`` times its
    canonical size: the object-to-camera transform and the grasp poses in the camera frame; None without a
    fitted camera beside the mesh."""
    c2w = fitted_camera_pose(mesh)
    if c2w is None:
        return None
    to_camera = object_to_camera(c2w, factor)
    return {
        "source": "prediction.json fit.camera",
        "convention": "OpenGL: x right, y up, the camera looks along -z",
        "object_to_camera": np.round(to_camera, 6).tolist(),
        "grasp_poses": np.round(poses_in_camera(poses, to_camera), 6).tolist(),
    }


def poses_in_camera(poses: np.ndarray, object_to_cam: np.ndarray) -> np.ndarray:
    """(G, 4, 4) grasp poses of the metric object frame, moved into the camera frame."""
    return np.einsum("ij,gjk->gik", object_to_cam, np.asarray(poses, np.float64).reshape(-1, 4, 4))
