"""``affnerf predict``: everything a user gets from one photo, written to one folder.

``input.png`` (the prepared crop), ``mask.png`` (the object mask used, at the photo's size: white = object, to
fix and pass back with ``--mask``), ``fit.png`` (after a fit to the photo: the crop beside the fitted model rendered
at the camera found), ``turntable/NNN.png`` (RGB | affordance overlay) and ``turntable.gif``,
``affordance_model.ply`` (vertex colours and an integer vertex property ``affordance``),
``affordance_model.glb``, and ``prediction.json`` (classes present, their surface areas, how confidently the object
was separated from its background, the photo's camera and the fit to the photo, the mesh or why there is none, the
files written).
Files are assembled in a temporary folder and moved into place at the end, so a failure leaves an earlier
prediction in the folder untouched.
"""

from __future__ import annotations

import json
import logging
import math
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X, Intrinsics
from affnerf.data.format import check_pose
from affnerf.fileio import read_json_file
from affnerf.meshio import LabelledMesh, write_labelled_ply
from affnerf.model.config import RAYS_PER_CHUNK
from affnerf.pictures.compose import overlay_affordance
from affnerf.predict.image import save_mask
from affnerf.predict.invert import InversionConfig, InversionResult
from affnerf.predict.mesh import class_areas
from affnerf.predict.predictor import EncodedObject, Predictor, turntable_poses
from affnerf.predict.segment import SHIPPED_SEGMENTER, SegmentMethod

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class PredictConfig:
    """Settings of ``affnerf predict``.

    Attributes:
        image: the photo of the object (any size and mode).
        out: output folder.
        run: a run folder or checkpoint (default: the model shipped with affnerf).
        mask: optional mask image (white or opaque = object), same size as the photo; it overrides ``segment``.
        segment: how to separate the object from its background without ``mask``: ``auto`` (the image's alpha,
            else a uniform background when the border is of one colour, else the object segmenter when it finds
            an object, else the salient-object model of the optional extra ``affnerf[segment]``, falling back to
            GrabCut with a warning without it), ``segmenter``, ``salient``, ``grabcut`` (OpenCV, from a centred
            rectangle), ``uniform`` (the border's colour) or ``none`` (the whole image is the object). The mask
            used is written as ``mask.png``.
        segmenter: the object segmenter of ``segment`` ``segmenter`` and ``auto`` (tried before the salient model):
            a file from ``affnerf train-segmenter`` (your own object families), ``none`` to leave it out, or
            ``shipped`` for the one shipped with affnerf (two U²-Net-p networks fine-tuned on the procedural
            families, voting).
        box: X0 Y0 X1 Y1, the rectangle of the photo the object lies in (pixels from the top-left corner, X1 and
            Y1 exclusive), as a detector or a drawn box gives it: ``segment`` runs inside it only, and everything
            outside is background (``auto``: the object segmenter's mask cut to the box when it is at least 80 %
            sure, else GrabCut from the box; the surest separation on a cluttered photo).
            ``mask`` (or, for ``auto``, the image's alpha) still comes first.
        views: turntable views.
        width: turntable image width.
        height: turntable image height.
        elevation: turntable camera elevation, degrees.
        radius: turntable camera distance, metres.
        resolution: marching-cubes grid resolution.
        level: density of the extracted surface (None: the object's own level from the model config:
            ``surface_density``, lowered for a diffuse object when ``surface_optical_depth`` is set).
        device: ``auto``, ``cpu`` or ``cuda``.
        chunk: rays per forward pass.
        fast: render and extract the mesh with the object's occupancy grid (empty-space skipping).
        grid_threshold: density above which a cell of the occupancy grid counts as occupied (None: the model
            config's ``occupancy_density``).
        fit_steps: steps of test-time inversion (:mod:`affnerf.predict.invert`): the photo's camera is searched
            and the encoder's codes are fitted to the photo's crop before anything is rendered or meshed; the
            camera found and the fit's losses go to ``prediction.json`` under ``fit``. 0 keeps the encoder's codes.
        fov: the photo's horizontal field of view, degrees (only the fit uses it).
    """

    image: Path
    out: Path
    run: Path | None = None
    mask: Path | None = None
    segment: SegmentMethod = "auto"
    segmenter: Path = SHIPPED_SEGMENTER
    box: tuple[int, int, int, int] | None = None
    views: int = 12
    width: int = 200
    height: int = 150
    elevation: float = 25.0
    radius: float = 0.75
    resolution: int = 128
    level: float | None = None
    device: str = "auto"
    chunk: int = RAYS_PER_CHUNK
    fast: bool = True
    grid_threshold: float | None = None
    fit_steps: int = 30
    fov: float = 60.0


def fit_record(result: InversionResult, steps: int, crop_fov_deg: float) -> dict[str, Any]:
    """The ``fit`` entry of ``prediction.json``: the photo's camera in the canonical frame (its angles and distance,
    and as a camera-to-canonical pose), the field of view of the crop the encoders saw, and the fit's losses."""
    az, el, dist = result.camera
    pose = result.camera_to_world()
    return {
        "steps": steps,
        "camera": {
            "azimuth_deg": round(math.degrees(az), 2),
            "elevation_deg": round(math.degrees(el), 2),
            "distance_m": round(dist, 4),
            "c2w": np.round(pose, 6).tolist(),
            "crop_fov_deg": round(crop_fov_deg, 3),
        },  # fmt: skip
        "silhouette_iou": round(result.search_iou, 4),
        "loss_before": round(result.loss_start, 5),
        "loss_after": round(result.loss_end, 5),
    }


def read_fit_camera(prediction: Path) -> tuple[np.ndarray, float | None] | None:
    """The camera a fitted prediction recorded (``fit.camera`` of its ``prediction.json``): the (4, 4)
    camera-to-canonical pose and the crop's field of view in degrees (None when absent). None when there is no such
    file, or it holds no fit (``--fit-steps 0``).

    Raises:
        AffnerfError: naming the file, when it is unreadable or the pose is not a rigid 4x4.
    """
    if not Path(prediction).is_file():
        return None
    data = read_json_file(Path(prediction))
    fit = data.get("fit") if isinstance(data, dict) else None
    camera = fit.get("camera") if isinstance(fit, dict) else None
    if not isinstance(camera, dict) or "c2w" not in camera:
        return None
    fov = camera.get("crop_fov_deg")
    return check_pose(camera["c2w"], Path(prediction), "fit.camera.c2w"), fov if isinstance(fov, int | float) else None


def export_glb(path: Path, mesh: LabelledMesh) -> None:
    """Write the mesh with its class colours as binary glTF."""
    data = mesh.to_trimesh().export(file_type="glb")
    path.write_bytes(data)


def _gif(frames: list[np.ndarray], path: Path) -> None:
    """An endlessly looping GIF, 120 ms a frame (identical neighbours are merged into one longer frame)."""
    images = [Image.fromarray(f) for f in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=120, loop=0)


#: Files a prediction writes only sometimes (the mesh when there is a surface, the fit's picture when it fits);
#: removed from OUT when a new prediction there does not write them.
OPTIONAL_FILES = ("affordance_model.ply", "affordance_model.glb", "fit.png")


def mesh_record(mesh: LabelledMesh, resolution: int, level: float) -> dict[str, Any]:
    """The ``mesh`` and ``mesh_note`` entries of ``prediction.json``: the mesh's size, or ``None`` with a note
    saying why there is no mesh."""
    if not len(mesh.faces):
        note = (f"the model predicts no surface: its density never reaches the surface level {level:g} in the "
                f"scene cube, so no mesh was written")  # fmt: skip
        return {"mesh": None, "mesh_note": note}
    size = {"vertices": len(mesh.vertices), "faces": len(mesh.faces), "resolution": resolution, "level": level}
    return {"mesh": size, "mesh_note": None}


def _clear_stale(out: Path, files: list[str]) -> None:
    """Remove from ``out`` the turntable folder and any mesh file the new prediction does not write."""
    if (out / "turntable").exists():
        shutil.rmtree(out / "turntable")
    for name in OPTIONAL_FILES:
        if name not in files and (out / name).is_file():
            (out / name).unlink()


#: Side of each panel of ``fit.png``, pixels.
FIT_PICTURE_SIDE = 128


def fit_picture(predictor: Predictor, obj: EncodedObject) -> np.ndarray:
    """(S, 3S, 3) uint8 check of the fit: the encoders' crop | the fitted model rendered at the camera the fit
    found, through the same crop | that render's affordance overlay. When the middle panel does not look like the
    first, the camera or the fit is wrong."""
    assert obj.inversion is not None and obj.crop_camera is not None and obj.prepared is not None
    crop_k = obj.crop_camera.scaled(FIT_PICTURE_SIDE / obj.crop_camera.width)
    pose = obj.inversion.camera_to_world()
    view = predictor.render(obj, crop_k, pose)
    rgb = np.round(np.clip(view.rgb, 0, 1) * 255).astype(np.uint8)
    side = (crop_k.width, crop_k.height)
    crop = np.asarray(Image.fromarray(obj.prepared.crop).resize(side, Image.BILINEAR))
    return np.concatenate([crop, rgb, overlay_affordance(rgb, view.labels)], axis=1)


def _write_mesh(folder: Path, mesh: LabelledMesh) -> list[str]:
    """Write ``affordance_model.ply`` and ``.glb`` into ``folder`` when the mesh has faces; returns their names."""
    if not len(mesh.faces):
        return []
    write_labelled_ply(folder / "affordance_model.ply", mesh)
    export_glb(folder / "affordance_model.glb", mesh)
    return ["affordance_model.ply", "affordance_model.glb"]


def _write_turntable(folder: Path, frames: list[np.ndarray]) -> list[str]:
    """Write ``turntable/NNN.png`` and ``turntable.gif`` into ``folder``; returns their names."""
    (folder / "turntable").mkdir()
    names = []
    for i, frame in enumerate(frames):
        Image.fromarray(frame).save(folder / "turntable" / f"{i:03d}.png")
        names.append(f"turntable/{i:03d}.png")
    _gif(frames, folder / "turntable.gif")
    return [*names, "turntable.gif"]


def write_prediction(predictor: Predictor, config: PredictConfig) -> dict[str, Any]:
    """Run the whole prediction and write its files; returns the content of ``prediction.json``.

    A model that predicts no surface gives no mesh: the other files are written, ``mesh`` is ``None`` with a
    ``mesh_note`` saying why, and a one-line warning names the checkpoint and the image.
    """
    obj = predictor.encode_image(config.image, config.mask, config.segment, config.segmenter, config.box)
    if config.fit_steps > 0:
        predictor.fit(obj, InversionConfig(steps=config.fit_steps), math.radians(config.fov))
    intr = Intrinsics.from_fov(config.width, config.height, DEFAULT_CAMERA_ANGLE_X)
    frames = []
    for pose in turntable_poses(config.views, config.elevation, config.radius):
        view = predictor.render(obj, intr, pose)
        rgb = np.round(view.rgb * 255).astype(np.uint8)
        frames.append(np.concatenate([rgb, overlay_affordance(rgb, view.labels)], axis=1))
    mesh, level = predictor.surface(obj, config.resolution, config.level)
    fit, check = None, None
    if obj.inversion is not None:
        mesh = predictor.confirm(obj, mesh, config.resolution, config.level)
        fit = fit_record(obj.inversion, config.fit_steps, math.degrees(obj.crop_camera.camera_angle_x))
        check = fit_picture(predictor, obj)
    out = Path(config.out)
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".predict-", dir=out))
    try:
        files = ["input.png", "mask.png"]
        Image.fromarray(obj.prepared.crop).save(tmp / "input.png")
        save_mask(tmp / "mask.png", obj.prepared.mask)
        if check is not None:
            Image.fromarray(check).save(tmp / "fit.png")
            files.append("fit.png")
        files += _write_turntable(tmp, frames)
        files += _write_mesh(tmp, mesh)
        areas = class_areas(mesh) if len(mesh.faces) else {}
        names = predictor.classes
        summary = {
            "image": str(config.image),
            "model": str(predictor.loaded.path),
            "model_step": predictor.loaded.step,
            "object_separated_by": obj.prepared.source,
            "separation": obj.prepared.separation.to_json(),
            "object_bbox": list(obj.prepared.bbox),
            "classes_present": [names[c] for c in sorted(areas)],
            "surface_area_m2": {names[c]: round(a, 6) for c, a in sorted(areas.items())},
            **mesh_record(mesh, config.resolution, level),
            "fit": fit,
            "files": files + ["prediction.json"],
        }
        (tmp / "prediction.json").write_text(json.dumps(summary, indent=1) + "\n")
        _clear_stale(out, files)
        for entry in os.listdir(tmp):
            os.replace(tmp / entry, out / entry)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if summary["mesh"] is None:
        logger.warning("%s: for %s, %s; lower --level or use a better-trained run", predictor.loaded.path,
                       config.image, summary["mesh_note"])  # fmt: skip
    return summary
