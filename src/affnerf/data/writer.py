"""Writing one object folder (conventions §2): rendered frames, ``mesh.ply`` and ``transforms.json``, all or nothing.

The folder is assembled under ``<root>/.partial/`` and renamed into place only when complete, so an object folder
that exists is whole; an interrupted write leaves only a stale temporary folder, removed by the next run.
"""

from __future__ import annotations

import os
import shutil
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from affnerf.data.cameras import Intrinsics
from affnerf.data.format import FrameRecord, IndexEntry, ObjectRecord, PartRecord
from affnerf.data.images import write_depth, write_labels, write_rgb
from affnerf.fileio import write_json_atomic
from affnerf.meshio import LabelledMesh, write_labelled_ply
from affnerf.objects.asset import Material, ObjectAsset, SurfaceMesh, merge_parts
from affnerf.vocab import AFFORDANCE_CLASSES

PARTIAL_DIR = ".partial"
DEPTH_UNIT = 0.001
MAP_FOLDERS = ("rgb", "depth", "affordance", "part")


def is_complete(folder: Path) -> bool:
    """Whether an object folder is complete (its ``transforms.json`` is written last, inside the temp folder)."""
    return (Path(folder) / "transforms.json").is_file()


def clear_partial(root: Path, object_id: str) -> None:
    """Remove temporary folders left by interrupted writes of ``object_id``."""
    partial = Path(root) / PARTIAL_DIR
    if partial.is_dir():
        for stale in partial.glob(f"{object_id}.*"):
            shutil.rmtree(stale, ignore_errors=True)


def surface_mesh_record(surface: SurfaceMesh) -> LabelledMesh:
    """The ground-truth ``mesh.ply`` content: geometry, part and affordance ids per face and vertex, base colours."""
    colors = np.array([m.color for m in surface.materials], np.float64)
    face_rgb = np.round(colors[surface.face_material] * 255).astype(np.uint8)
    vertex_rgb = np.zeros((len(surface.vertices), 3), np.uint8)
    vertex_rgb[surface.faces.reshape(-1)] = np.repeat(face_rgb, 3, axis=0)
    return LabelledMesh(
        vertices=surface.vertices,
        faces=surface.faces,
        vertex_props={"part": surface.vertex_part, "affordance": surface.vertex_affordance},
        face_props={"part": surface.face_part, "affordance": surface.face_affordance},
        vertex_colors=vertex_rgb,
    )


def surface_from_record(mesh: LabelledMesh) -> SurfaceMesh:
    """The renderable surface of a ground-truth ``mesh.ply`` (the inverse of :func:`surface_mesh_record`, with
    each face in its first vertex's colour)."""
    face_rgb = (
        mesh.vertex_colors[mesh.faces[:, 0]] if mesh.vertex_colors is not None else np.full((len(mesh.faces), 3), 180)
    )
    colors, face_material = np.unique(face_rgb, axis=0, return_inverse=True)
    n = len(mesh.faces)
    return SurfaceMesh(
        vertices=np.asarray(mesh.vertices, np.float64),
        faces=np.asarray(mesh.faces, np.int64),
        face_part=np.asarray(mesh.face_props.get("part", np.ones(n)), np.uint8),
        face_affordance=np.asarray(mesh.face_props["affordance"], np.uint8),
        face_material=face_material.reshape(-1).astype(np.int32),
        face_uv=np.zeros((n, 3, 2), np.float32),
        materials=[Material(tuple(float(c) / 255.0 for c in rgb)) for rgb in colors],  # type: ignore[misc]
    )


def swap_in(root: Path, new: Path, final: Path, object_id: str) -> None:
    """Replace the complete folder ``final`` by the complete folder ``new``: two renames, the old copy deleted last.

    The old folder is first moved under ``root/.partial/``; if moving ``new`` into place then fails, it is moved
    back, so a failure leaves the old copy where it was.
    """
    old = Path(root) / PARTIAL_DIR / f"{object_id}.replaced.{os.getpid()}.{uuid.uuid4().hex[:8]}"
    os.rename(final, old)
    try:
        os.rename(new, final)
    except BaseException:
        os.rename(old, final)
        raise
    shutil.rmtree(old, ignore_errors=True)


def frame_paths(index: int, digits: int) -> tuple[str, str, str, str]:
    """Relative paths of the four maps of frame ``index`` (e.g. ``rgb/007.png``)."""
    name = f"{index:0{digits}d}.png"
    return tuple(f"{folder}/{name}" for folder in MAP_FOLDERS)  # type: ignore[return-value]


def _write_frames(
    folder: Path,
    surface: SurfaceMesh,
    poses: np.ndarray,
    intrinsics: Intrinsics,
    background: tuple[float, float, float],
    on_frame: Callable[[], None] | None,
) -> list[FrameRecord]:
    """Ray-cast every pose and write its four maps under ``folder``; returns the frames' records."""
    from affnerf.data.raycast import FrameCaster  # loaded late: see affnerf.data.pool on the ray caster's threads

    for sub in MAP_FOLDERS:
        (folder / sub).mkdir(parents=True)
    caster = FrameCaster(surface, background)
    digits = max(3, len(str(len(poses) - 1)))
    frames = []
    for i, pose in enumerate(poses):
        frame = caster.cast_frame(intrinsics, pose)
        paths = frame_paths(i, digits)
        write_rgb(folder / paths[0], frame.rgb)
        write_depth(folder / paths[1], frame.depth, DEPTH_UNIT)
        write_labels(folder / paths[2], frame.affordance)
        write_labels(folder / paths[3], frame.part)
        frames.append(FrameRecord(*paths, transform_matrix=np.asarray(pose)))
        if on_frame is not None:
            on_frame()
    return frames


def object_record(
    entry: IndexEntry,
    asset: ObjectAsset,
    intrinsics: Intrinsics,
    background: tuple[float, float, float],
    frames: list[FrameRecord],
    extra: dict[str, Any] | None = None,
) -> ObjectRecord:
    """The ``transforms.json`` content of an object: cameras, parts, frames, and its split, source, scale, joint
    states and shape parameters (plus ``extra``)."""
    return ObjectRecord(
        object_id=entry.id,
        category=entry.category,
        intrinsics=intrinsics,
        background_color=background,
        depth_unit_scale_factor=DEPTH_UNIT,
        affordance_classes=list(AFFORDANCE_CLASSES),
        parts=[PartRecord(**p) for p in asset.part_table()],
        frames=frames,
        extra={
            "split": entry.split,
            "source": entry.source,
            "scale": asset.scale,
            "joints": [j.to_json() for j in asset.joints],
            "params": asset.params,
            **(extra or {}),
        },
    )


def _move_into_place(root: Path, tmp: Path, final: Path, object_id: str, replace: bool) -> None:
    """Put the finished folder ``tmp`` at ``final``: swap it in (``replace``), keep a complete copy already there
    (another process finished first), or clear debris and rename."""
    final.parent.mkdir(parents=True, exist_ok=True)
    if is_complete(final) and replace:
        swap_in(root, tmp, final, object_id)
    elif is_complete(final):
        shutil.rmtree(tmp)
    else:
        if final.exists():  # a folder without transforms.json is debris, never a finished object
            shutil.rmtree(final)
        os.rename(tmp, final)


def write_object(
    root: Path,
    entry: IndexEntry,
    asset: ObjectAsset,
    poses: np.ndarray,
    intrinsics: Intrinsics,
    background: tuple[float, float, float] = (1.0, 1.0, 1.0),
    extra: dict[str, Any] | None = None,
    on_frame: Callable[[], None] | None = None,
    replace: bool = False,
) -> Path:
    """Ray-cast ``asset`` from every pose and write its complete folder at ``root / entry.path``, all or nothing
    (assembled under ``.partial/``, then renamed into place).

    Args:
        root: dataset root.
        entry: the object's index entry (id, category, relative path, split, source).
        asset: the object, in its canonical frame.
        poses: (N, 4, 4) camera-to-world poses.
        intrinsics: the camera.
        background: RGB in [0, 1]; use multiples of 1/255 so background pixels equal it exactly.
        extra: more keys for ``transforms.json``.
        on_frame: called after each frame is written (progress).
        replace: replace a complete folder already there (see :func:`swap_in`); by default it is kept.

    Returns:
        The object folder.
    """
    root = Path(root)
    final = root / entry.path
    clear_partial(root, entry.id)
    tmp = root / PARTIAL_DIR / f"{entry.id}.{os.getpid()}.{uuid.uuid4().hex[:8]}"
    try:
        surface = merge_parts(asset)
        frames = _write_frames(tmp, surface, poses, intrinsics, background, on_frame)
        write_labelled_ply(tmp / "mesh.ply", surface_mesh_record(surface))
        record = object_record(entry, asset, intrinsics, background, frames, extra)
        write_json_atomic(tmp / "transforms.json", record.to_json())
        _move_into_place(root, tmp, final, entry.id, replace)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return final
