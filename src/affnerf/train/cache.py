"""Training frames as uint8 memory maps: decoded once at the training resolution, never held as float tensors.

For each object a folder holds ``rgb.npy`` (N, H, W, 3), ``labels.npy`` (N, H, W) affordance ids, ``depth.npy``
(N, H, W) float16 z-depth in metres (0 = no surface), ``crops.npy``
(N, S, S, 3) encoder crops, the object's pixels of every frame (``fg_pixels.npy``, flat indices, frame i's
between ``fg_offsets.npy[i]`` and ``[i + 1]``) and ``meta.json`` (poses, intrinsics, background, and a hash of the
source ``transforms.json``, so a regenerated object is decoded again). With 3D supervision on, a folder
``<id>.points`` beside it holds the object's :class:`~affnerf.train.points.PointSet` (``points.npy`` (N, 3) float32,
``occupancy.npy`` (N,) uint8, ``point_labels.npy`` (N,) uint8, ``point_distance.npy`` (N,) float16) and a
``meta.json`` whose signature hashes the source ``mesh.ply`` and the sampling settings. Folders are written under a
temporary name and renamed, so a crash never leaves a half cache that looks complete.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.data.crop import crop_intrinsics, crop_object, crop_window
from affnerf.data.dataset import ObjectData
from affnerf.errors import input_error
from affnerf.meshio import read_labelled_ply
from affnerf.train.points import POINT_SET_SIZE, UNIFORM_SHARE, PointSet, make_point_set


@dataclass
class ObjectFrames:
    """One object's training frames (memory-mapped, read-only).

    Attributes:
        object_id: the dataset id.
        rgb: (N, H, W, 3) uint8.
        labels: (N, H, W) uint8 affordance ids.
        depth: (N, H, W) float16 z-depth in metres, 0 where no surface (nearest-resized like the labels).
        crops: (N, S, S, 3) uint8 encoder crops.
        crop_intrinsics: (N, 4) fl_x, fl_y, cx, cy of each crop (for pixel-aligned baselines).
        fg_offsets: (N + 1,) start of each frame's object pixels in ``fg_pixels``.
        fg_pixels: (M,) flat pixel indices (v * W + u) of the object's pixels, frame after frame.
        poses: (N, 4, 4) float64 camera-to-world.
        intrinsics: (4,) fl_x, fl_y, cx, cy at the cached resolution.
        background: (3,) RGB in [0, 1].
    """

    object_id: str
    rgb: np.ndarray
    labels: np.ndarray
    depth: np.ndarray
    crops: np.ndarray
    crop_intrinsics: np.ndarray
    fg_offsets: np.ndarray
    fg_pixels: np.ndarray
    poses: np.ndarray
    intrinsics: np.ndarray
    background: np.ndarray

    def __len__(self) -> int:
        return len(self.poses)


#: Bumped when the cache's layout changes, so older caches are rebuilt.
CACHE_VERSION = 3


def _signature(obj: ObjectData, scale: float, crop: int) -> str:
    digest = hashlib.sha1((obj.folder / "transforms.json").read_bytes()).hexdigest()[:16]
    return f"v{CACHE_VERSION}-{digest}-{scale:g}-{crop}"


def pixel_index(masks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (N + 1,) and flat pixel indices (M,) of the True pixels of (N, H, W) masks, frame after frame (frame
    i's between ``offsets[i]`` and ``offsets[i + 1]``)."""
    per_frame = [np.flatnonzero(masks[i].reshape(-1)).astype(np.int32) for i in range(len(masks))]
    offsets = np.concatenate([[0], np.cumsum([len(f) for f in per_frame])]).astype(np.int64)
    return offsets, (np.concatenate(per_frame) if per_frame else np.zeros(0, np.int32))


def foreground_index(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (N + 1,) and flat pixel indices (M,) of the object pixels of (N, H, W) label maps."""
    return pixel_index(labels > 0)


def part_edge_index(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (N + 1,) and flat pixel indices (M,) of the part edges of (N, H, W) label maps: the object pixels
    with an object pixel of another class among their eight neighbours (edges with the background not counted).

    Example:
        >>> labels = np.zeros((1, 3, 4), np.uint8); labels[0, :, 1] = 1; labels[0, :, 2] = 2
        >>> offsets, pixels = part_edge_index(labels)
        >>> offsets.tolist(), pixels.tolist()
        ([0, 6], [1, 2, 5, 6, 9, 10])
    """
    _, h, w = labels.shape
    padded = np.pad(labels, ((0, 0), (1, 1), (1, 1)))
    edge = np.zeros(labels.shape, bool)
    for dv in (-1, 0, 1):
        for du in (-1, 0, 1):
            other = padded[:, 1 + dv : 1 + dv + h, 1 + du : 1 + du + w]
            edge |= (other > 0) & (other != labels)
    return pixel_index(edge & (labels > 0))


def frames_from_arrays(
    object_id: str,
    rgb: np.ndarray,
    labels: np.ndarray,
    poses: np.ndarray,
    intrinsics: np.ndarray,
    background: np.ndarray,
) -> ObjectFrames:
    """Frames held in memory (for fitting a per-object field), without encoder crops.

    Args:
        rgb: (N, H, W, 3) uint8; labels: (N, H, W) uint8; poses: (N, 4, 4); intrinsics: (4,); background: (3,).
    """
    offsets, pixels = foreground_index(labels)
    n = len(rgb)
    return ObjectFrames(
        object_id,
        rgb,
        labels,
        np.zeros(labels.shape, np.float16),
        np.zeros((n, 1, 1, 3), np.uint8),
        np.zeros((n, 4)),
        offsets,
        pixels,
        np.asarray(poses, np.float64),
        np.asarray(intrinsics, np.float64),
        np.asarray(background, np.float64),
    )


def _resize(image: np.ndarray, size: tuple[int, int], nearest: bool) -> np.ndarray:
    if (image.shape[1], image.shape[0]) == size:
        return image
    return np.asarray(Image.fromarray(image).resize(size, Image.NEAREST if nearest else Image.BOX))


def write_folder(folder: Path, fill: Callable[[Path], None]) -> None:
    """Make ``folder`` atomically: ``fill`` writes into a temporary sibling, which then replaces ``folder``."""
    tmp = folder.parent / f".{folder.name}.{uuid.uuid4().hex[:8]}"
    tmp.mkdir(parents=True)
    try:
        fill(tmp)
        if folder.exists():
            shutil.rmtree(folder)
        os.rename(tmp, folder)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def build_frames(obj: ObjectData, folder: Path, scale: float, crop_size: int) -> None:
    """Decode an object's frames into a cache folder (see the module docstring)."""
    write_folder(folder, lambda tmp: _write_frames(obj, tmp, scale, crop_size))


def _write_frames(obj: ObjectData, tmp: Path, scale: float, crop_size: int) -> None:
    intr = obj.record.intrinsics.scaled(scale)
    size = (intr.width, intr.height)
    n = len(obj)
    rgb = np.lib.format.open_memmap(tmp / "rgb.npy", "w+", np.uint8, (n, size[1], size[0], 3))
    labels = np.lib.format.open_memmap(tmp / "labels.npy", "w+", np.uint8, (n, size[1], size[0]))
    depth = np.lib.format.open_memmap(tmp / "depth.npy", "w+", np.float16, (n, size[1], size[0]))
    crops = np.lib.format.open_memmap(tmp / "crops.npy", "w+", np.uint8, (n, crop_size, crop_size, 3))
    background = obj.record.background_color
    full = obj.record.intrinsics
    crop_k = []
    for i in range(n):
        full_rgb, full_aff = obj.rgb(i), obj.affordance(i)
        crops[i] = crop_object(full_rgb, full_aff > 0, crop_size, background)
        window = crop_window(full_aff > 0)
        crop_k.append(crop_intrinsics(full.fl_x, full.fl_y, full.cx, full.cy, window, crop_size))
        rgb[i] = _resize(full_rgb, size, nearest=False)
        labels[i] = _resize(full_aff, size, nearest=True)
        depth[i] = _resize(obj.depth(i), size, nearest=True)
    for array in (rgb, labels, depth, crops):
        array.flush()
    offsets, pixels = foreground_index(labels)
    np.save(tmp / "fg_offsets.npy", offsets)
    np.save(tmp / "fg_pixels.npy", pixels)
    del rgb, labels, depth, crops
    meta = {
        "signature": _signature(obj, scale, crop_size),
        "object_id": obj.record.object_id,
        "poses": obj.poses.tolist(),
        "intrinsics": [intr.fl_x, intr.fl_y, intr.cx, intr.cy],
        "crop_intrinsics": crop_k,
        "background": list(background),
    }
    (tmp / "meta.json").write_text(json.dumps(meta))


def load_frames(folder: Path) -> ObjectFrames:
    """Open a cache folder written by :func:`build_frames`."""
    meta = json.loads((folder / "meta.json").read_text())
    return ObjectFrames(
        object_id=meta["object_id"],
        rgb=np.load(folder / "rgb.npy", mmap_mode="r"),
        labels=np.load(folder / "labels.npy", mmap_mode="r"),
        depth=np.load(folder / "depth.npy", mmap_mode="r"),
        crops=np.load(folder / "crops.npy", mmap_mode="r"),
        crop_intrinsics=np.asarray(meta["crop_intrinsics"], np.float64),
        fg_offsets=np.load(folder / "fg_offsets.npy"),
        fg_pixels=np.load(folder / "fg_pixels.npy", mmap_mode="r"),
        poses=np.asarray(meta["poses"], np.float64),
        intrinsics=np.asarray(meta["intrinsics"], np.float64),
        background=np.asarray(meta["background"], np.float64),
    )


def cached_frames(obj: ObjectData, cache_dir: Path, scale: float, crop_size: int) -> ObjectFrames:
    """The object's cached frames, decoding them first if the cache is missing or stale."""
    folder = Path(cache_dir) / f"{obj.record.object_id}"
    meta = folder / "meta.json"
    fresh = meta.is_file() and json.loads(meta.read_text()).get("signature") == _signature(obj, scale, crop_size)
    if not fresh:
        build_frames(obj, folder, scale, crop_size)
    return load_frames(folder)


#: Bumped when point sets are made differently, so older ones are rebuilt.
POINTS_VERSION = 4


def _points_signature(
    mesh_path: Path,
    half_extent: float,
    sigmas: tuple[float, ...],
    total: int,
    part_balance: float = 0.0,
    uniform_share: float = UNIFORM_SHARE,
) -> str:
    digest = hashlib.sha1(Path(mesh_path).read_bytes()).hexdigest()[:16]
    # sets drawn as before keep their older signature
    balance = f"-b{part_balance:g}" if part_balance > 0 else ""
    uniform = f"-u{uniform_share:g}" if uniform_share != UNIFORM_SHARE else ""
    return f"p{POINTS_VERSION}-{digest}-{half_extent:g}-{','.join(f'{s:g}' for s in sigmas)}-{total}{balance}{uniform}"


def _write_points(
    tmp: Path,
    mesh_path: Path,
    seed: int,
    half_extent: float,
    sigmas: tuple,
    total: int,
    part_balance: float,
    uniform_share: float,
) -> None:
    mesh = read_labelled_ply(mesh_path)
    if "affordance" not in mesh.face_props:
        raise input_error(mesh_path, "mesh has no per-face 'affordance' property (needed by --points-weight)")
    points = make_point_set(mesh, half_extent, sigmas, seed, total, part_balance, uniform_share)
    np.save(tmp / "points.npy", points.points)
    np.save(tmp / "occupancy.npy", points.occupancy)
    np.save(tmp / "point_labels.npy", points.labels)
    np.save(tmp / "point_distance.npy", points.distance)
    signature = _points_signature(mesh_path, half_extent, sigmas, total, part_balance, uniform_share)
    (tmp / "meta.json").write_text(json.dumps({"signature": signature, "seed": seed}))


def load_points(folder: Path) -> PointSet:
    """Open a point folder written by :func:`cached_points` (memory-mapped, read-only)."""
    names = ("points.npy", "occupancy.npy", "point_labels.npy", "point_distance.npy")
    return PointSet(*(np.load(folder / name, mmap_mode="r") for name in names))


def cached_points(
    mesh_path: Path,
    object_id: str,
    cache_dir: Path,
    half_extent: float,
    sigmas: tuple[float, ...],
    total: int = POINT_SET_SIZE,
    part_balance: float = 0.0,
    uniform_share: float = UNIFORM_SHARE,
) -> PointSet:
    """The object's supervision points (``<cache_dir>/<object_id>.points``), made from ``mesh_path`` first if
    they are missing or stale (another mesh, cube, sigmas or part balance); the draws are seeded by the object id
    alone.

    Args:
        mesh_path: the object's ``mesh.ply``; object_id: its dataset id; cache_dir: the frame cache's folder;
        half_extent: half the scene cube's side (m); sigmas: near-surface noise sigmas (m); total: N;
        part_balance: the near-surface samples' part weighting (:func:`affnerf.train.points.part_face_weights`);
        uniform_share: the share of the N points drawn uniformly over the cube.
    """
    if not Path(mesh_path).is_file():
        raise input_error(mesh_path, "file not found (--points-weight needs each training object's mesh.ply)")
    folder = Path(cache_dir) / f"{object_id}.points"
    meta = folder / "meta.json"
    signature = _points_signature(mesh_path, half_extent, sigmas, total, part_balance, uniform_share)
    if not (meta.is_file() and json.loads(meta.read_text()).get("signature") == signature):
        seed = zlib.crc32(object_id.encode())
        draw = (half_extent, sigmas, total, part_balance, uniform_share)
        write_folder(folder, lambda tmp: _write_points(tmp, mesh_path, seed, *draw))
    return load_points(folder)
