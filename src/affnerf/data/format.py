"""The dataset format (conventions §2): ``dataset.json`` and each object's ``transforms.json``, read and validated.

Readers check what later stages rely on (format version, finite rigid poses, sizes, class lists) and report a
problem as one line naming the file. Writers are atomic: a temporary file renamed over the target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from affnerf.data.cameras import Intrinsics
from affnerf.errors import input_error
from affnerf.fileio import read_json_file

#: Format tag of ``dataset.json``.
FORMAT = "affnerf-1"
SPLITS = ("train", "val", "test", "unseen")
SOURCES = ("procedural", "partnet-mobility")


def check_pose(matrix: Any, where: Path, what: str = "transform_matrix", tol: float = 1e-3) -> np.ndarray:
    """Validate a camera-to-world pose and return it as (4, 4) float64.

    Raises:
        AffnerfError: when it is missing, not 4x4, not finite, or its rotation is not rigid.
    """
    if matrix is None:
        raise input_error(where, f"{what} is missing")
    try:
        m = np.asarray(matrix, dtype=np.float64)
    except (TypeError, ValueError):
        raise input_error(where, f"{what} is not a numeric matrix") from None
    if m.shape != (4, 4):
        raise input_error(where, f"{what} has shape {m.shape}, expected 4x4")
    if not np.isfinite(m).all():
        raise input_error(where, f"{what} has NaN or infinite entries")
    r = m[:3, :3]
    if not np.allclose(r.T @ r, np.eye(3), atol=tol) or abs(np.linalg.det(r) - 1.0) > tol:
        raise input_error(where, f"{what} rotation is not rigid (orthonormal with determinant 1)")
    if not np.allclose(m[3], [0, 0, 0, 1], atol=tol):
        raise input_error(where, f"{what} last row is {m[3].tolist()}, expected [0, 0, 0, 1]")
    return m


@dataclass(frozen=True)
class FrameRecord:
    """One view of an object: paths relative to the object folder and its camera-to-world pose (4, 4)."""

    file_path: str
    depth_file_path: str
    affordance_file_path: str
    part_file_path: str
    transform_matrix: np.ndarray


@dataclass(frozen=True)
class PartRecord:
    """A part of an object: id in the part maps, name and affordance name."""

    id: int
    name: str
    affordance: str


@dataclass
class ObjectRecord:
    """The contents of one ``transforms.json``.

    Attributes:
        object_id: unique id within the dataset.
        category: category name.
        intrinsics: the camera of every frame.
        background_color: RGB in [0, 1] of background pixels.
        depth_unit_scale_factor: metres per unit of the depth PNGs.
        affordance_classes: class names indexed by id (same list as dataset.json).
        parts: the parts and their affordances.
        frames: the views.
        extra: every other key (split, source, scale, joints, params, ...), kept as read.
    """

    object_id: str
    category: str
    intrinsics: Intrinsics
    background_color: tuple[float, float, float]
    depth_unit_scale_factor: float
    affordance_classes: list[str]
    parts: list[PartRecord]
    frames: list[FrameRecord]
    extra: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """The JSON form (conventions §2)."""
        intr = self.intrinsics
        out: dict[str, Any] = {
            "object_id": self.object_id,
            "category": self.category,
            "w": intr.width,
            "h": intr.height,
            "fl_x": intr.fl_x,
            "fl_y": intr.fl_y,
            "cx": intr.cx,
            "cy": intr.cy,
            "camera_angle_x": intr.camera_angle_x,
            "background_color": [float(c) for c in self.background_color],
            "depth_unit_scale_factor": self.depth_unit_scale_factor,
            "affordance_classes": list(self.affordance_classes),
            "parts": [{"id": p.id, "name": p.name, "affordance": p.affordance} for p in self.parts],
        }
        out.update(self.extra)
        out["frames"] = [
            {
                "file_path": f.file_path,
                "depth_file_path": f.depth_file_path,
                "affordance_file_path": f.affordance_file_path,
                "part_file_path": f.part_file_path,
                "transform_matrix": np.asarray(f.transform_matrix).tolist(),
            }
            for f in self.frames
        ]
        return out


_CORE_KEYS = {
    "object_id",
    "category",
    "w",
    "h",
    "fl_x",
    "fl_y",
    "cx",
    "cy",
    "camera_angle_x",
    "background_color",
    "depth_unit_scale_factor",
    "affordance_classes",
    "parts",
    "frames",
}


def _number(data: dict, key: str, path: Path, positive: bool = False) -> float:
    value = data.get(key)
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise input_error(path, f"{key!r} must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise input_error(path, f"{key!r} must be positive, got {value!r}")
    return float(value)


def parse_transforms(data: Any, path: Path) -> ObjectRecord:
    """Validate the parsed JSON of a ``transforms.json`` (``path`` names it in errors)."""
    if not isinstance(data, dict):
        raise input_error(path, "expected a JSON object")
    for key in ("object_id", "category", "frames", "parts", "affordance_classes"):
        if key not in data:
            raise input_error(path, f"missing key {key!r}")
    width, height = int(_number(data, "w", path, True)), int(_number(data, "h", path, True))
    intr = Intrinsics(
        width,
        height,
        _number(data, "fl_x", path, True),
        _number(data, "fl_y", path, True),
        _number(data, "cx", path),
        _number(data, "cy", path),
    )
    classes = data["affordance_classes"]
    if not isinstance(classes, list) or not classes or not all(isinstance(c, str) for c in classes):
        raise input_error(path, "'affordance_classes' must be a non-empty list of names")
    parts = []
    for p in data["parts"]:
        if not isinstance(p, dict) or {"id", "name", "affordance"} - set(p):
            raise input_error(path, f"part entry {p!r} needs 'id', 'name' and 'affordance'")
        if p["affordance"] not in classes:
            raise input_error(path, f"part {p['name']!r} has unknown affordance {p['affordance']!r}")
        if not isinstance(p["id"], int) or not 1 <= p["id"] <= 255:
            raise input_error(path, f"part {p['name']!r} has id {p['id']!r}, expected 1..255")
        parts.append(PartRecord(int(p["id"]), str(p["name"]), str(p["affordance"])))
    frames = []
    if not isinstance(data["frames"], list) or not data["frames"]:
        raise input_error(path, "'frames' must be a non-empty list")
    for i, f in enumerate(data["frames"]):
        keys = ("file_path", "depth_file_path", "affordance_file_path", "part_file_path")
        if not isinstance(f, dict) or any(not isinstance(f.get(k), str) for k in keys):
            raise input_error(path, f"frame {i} needs the paths {', '.join(keys)}")
        pose = check_pose(f.get("transform_matrix"), path, f"frame {i} transform_matrix")
        frames.append(FrameRecord(*(f[k] for k in keys), transform_matrix=pose))
    background = data.get("background_color", [1.0, 1.0, 1.0])
    if not (isinstance(background, list) and len(background) == 3 and all(0 <= float(c) <= 1 for c in background)):
        raise input_error(path, f"'background_color' must be three numbers in [0, 1], got {background!r}")
    unit = _number(data, "depth_unit_scale_factor", path, True) if "depth_unit_scale_factor" in data else 0.001
    return ObjectRecord(
        object_id=str(data["object_id"]),
        category=str(data["category"]),
        intrinsics=intr,
        background_color=(float(background[0]), float(background[1]), float(background[2])),
        depth_unit_scale_factor=unit,
        affordance_classes=list(classes),
        parts=parts,
        frames=frames,
        extra={k: v for k, v in data.items() if k not in _CORE_KEYS},
    )


def read_transforms(path: Path) -> ObjectRecord:
    """Read and validate one object's ``transforms.json``."""
    return parse_transforms(read_json_file(path), Path(path))


@dataclass(frozen=True)
class IndexEntry:
    """One object of ``dataset.json``: id, category, folder (relative to the root), split and source."""

    id: str
    category: str
    path: str
    split: str
    source: str

    def to_json(self) -> dict[str, str]:
        return {"id": self.id, "category": self.category, "path": self.path, "split": self.split, "source": self.source}


@dataclass
class DatasetIndex:
    """The contents of ``dataset.json``; ``extra`` keeps other keys (such as the generation settings)."""

    affordance_classes: list[str]
    objects: list[IndexEntry]
    extra: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"format": FORMAT, "affordance_classes": list(self.affordance_classes)}
        out.update(self.extra)
        out["objects"] = [o.to_json() for o in self.objects]
        return out


def parse_index(data: Any, path: Path) -> DatasetIndex:
    """Validate the parsed JSON of a ``dataset.json``."""
    if not isinstance(data, dict):
        raise input_error(path, "expected a JSON object")
    if data.get("format") != FORMAT:
        raise input_error(path, f"format is {data.get('format')!r}; this version of affnerf reads {FORMAT!r}")
    classes = data.get("affordance_classes")
    if not isinstance(classes, list) or not classes:
        raise input_error(path, "'affordance_classes' must be a non-empty list")
    objects = []
    for o in data.get("objects", []):
        if not isinstance(o, dict) or {"id", "category", "path", "split"} - set(o):
            raise input_error(path, f"object entry {o!r} needs 'id', 'category', 'path' and 'split'")
        if o["split"] not in SPLITS:
            raise input_error(path, f"object {o['id']!r} has split {o['split']!r}, expected one of {SPLITS}")
        objects.append(IndexEntry(o["id"], o["category"], o["path"], o["split"], o.get("source", "procedural")))
    ids = [o.id for o in objects]
    if len(set(ids)) != len(ids):
        raise input_error(path, "object ids are not unique")
    extra = {k: v for k, v in data.items() if k not in ("format", "affordance_classes", "objects")}
    return DatasetIndex(list(classes), objects, extra)


def read_index(root: Path) -> DatasetIndex:
    """Read and validate ``root/dataset.json``."""
    path = Path(root) / "dataset.json"
    if not Path(root).is_dir():
        raise input_error(root, "dataset folder not found")
    return parse_index(read_json_file(path), path)
