"""Wavefront OBJ + MTL reading with per-face-corner UVs and per-face materials.

A small reader of its own rather than ``trimesh.load``: trimesh splits a multi-material OBJ into a Scene ordered by
material and re-indexes vertices to carry one UV each, while the importer needs the faces in file order with the
UV of every face corner (PartNet-Mobility files mix faces with and without ``vt`` in one mesh) and textures
shared between the OBJs of an object (loaded once).

Supported: ``v``, ``vt``, ``f`` (triangles and polygons, fan-triangulated; ``v``, ``v/vt``, ``v//vn``,
``v/vt/vn``; negative indices), ``usemtl``, ``mtllib``; in MTL files ``newmtl``, ``Kd`` and ``map_Kd``. Appearance
problems (a missing MTL file or texture image, an unknown material) fall back to plain colours with a warning;
geometry problems are errors.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.errors import input_error
from affnerf.objects.asset import Material

logger = logging.getLogger(__name__)

#: Material of faces before any ``usemtl`` or naming an unknown material.
DEFAULT_MATERIAL = Material()


@dataclass(frozen=True)
class ObjMesh:
    """A triangle mesh read from an OBJ file, faces in file order.

    Attributes:
        vertices: (V, 3) float64 positions (only vertices some face uses).
        faces: (F, 3) int64 indices into ``vertices``.
        face_uv: (F, 3, 2) float64 texture coordinates per face corner (zeros for faces without ``vt``), or
            ``None`` when no face has any.
        face_material: (F,) int32 index into ``materials``.
        materials: the materials the faces use, in order of first use.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_uv: np.ndarray | None
    face_material: np.ndarray
    materials: tuple[Material, ...]


def load_texture(path: Path, cache: dict[Path, np.ndarray | None]) -> np.ndarray | None:
    """An image as (H, W, 3) uint8 (alpha dropped), loaded once per path; ``None`` with a warning if unreadable."""
    key = path.resolve()
    if key not in cache:
        try:
            with Image.open(key) as img:
                cache[key] = np.asarray(img.convert("RGB"), dtype=np.uint8)
        except (OSError, ValueError) as exc:
            logger.warning("%s: cannot read texture image (%s); using the plain colour", path, exc)
            cache[key] = None
    return cache[key]


def read_mtl(path: Path, textures: dict[Path, np.ndarray | None]) -> dict[str, Material]:
    """The materials of an MTL file: ``Kd`` as colour, ``map_Kd`` (relative to the file) as texture.

    Args:
        path: the ``.mtl`` file.
        textures: cache of loaded images (see :func:`load_texture`), shared between files.

    Returns:
        ``{material name: Material}``; a textured material without ``Kd`` is white, an untextured one without
        ``Kd`` has the default colour. A missing or unreadable file gives ``{}`` with a warning.
    """
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        logger.warning("%s: cannot read material file (%s); using plain colours", path, exc)
        return {}
    found: dict[str, dict[str, object]] = {}
    current: dict[str, object] | None = None
    for number, line in enumerate(lines, start=1):
        parts = line.split()
        if not parts or parts[0].startswith("#"):
            continue
        key = parts[0]
        if key == "newmtl":
            current = found.setdefault(" ".join(parts[1:]), {})
        elif current is None:
            continue
        elif key == "Kd" and len(parts) >= 4:
            try:
                rgb = tuple(min(max(float(x), 0.0), 1.0) for x in parts[1:4])
            except ValueError:
                logger.warning("%s: line %d: unreadable Kd %r; ignored", path, number, line.strip())
                continue
            current["color"] = rgb
        elif key == "map_Kd" and len(parts) >= 2:
            image_path = path.parent / parts[-1].replace("\\", "/")  # options such as -s come before the file
            current["texture"] = load_texture(image_path, textures)
    materials = {}
    for name, spec in found.items():
        texture = spec.get("texture")
        default = (1.0, 1.0, 1.0) if texture is not None else DEFAULT_MATERIAL.color
        materials[name] = Material(color=spec.get("color", default), texture=texture)  # type: ignore[arg-type]
    return materials


def _index(token: str, count: int, path: Path, number: int) -> int:
    """0-based index of an OBJ index token (1-based, or negative counting back from ``count``)."""
    try:
        i = int(token)
    except ValueError:
        raise input_error(path, f"line {number}: bad index {token!r}") from None
    j = i - 1 if i > 0 else count + i
    if i == 0 or not 0 <= j < count:
        raise input_error(path, f"line {number}: index {i} out of range (1..{count})")
    return j


@dataclass
class ObjRecords:
    """What the lines of an OBJ file declare, in file order (faces fan-triangulated, indices 0-based).

    Attributes:
        verts: ``v`` positions.
        uvs: ``vt`` coordinates (u, v).
        faces: triangles as indices into ``verts``.
        face_uv: per triangle, indices into ``uvs`` of its corners, or ``None`` when the face has no ``vt``.
        face_material: per triangle, its material's index in ``used``.
        library: the materials of the ``mtllib`` files, by name.
        used: material name -> index, in order of first use (``""`` before any ``usemtl``).
        current: the material named by the last ``usemtl``.
    """

    verts: list[list[float]] = field(default_factory=list)
    uvs: list[list[float]] = field(default_factory=list)
    faces: list[list[int]] = field(default_factory=list)
    face_uv: list[list[int] | None] = field(default_factory=list)
    face_material: list[int] = field(default_factory=list)
    library: dict[str, Material] = field(default_factory=dict)
    used: dict[str, int] = field(default_factory=dict)
    current: str = ""


def read_lines(path: Path) -> list[str]:
    """The lines of a text file (undecodable bytes replaced).

    Raises:
        AffnerfError: naming the file, when it is missing or unreadable.
    """
    if not path.is_file():
        raise input_error(path, "file not found")
    try:
        return path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise input_error(path, f"cannot read ({exc})") from None


def parse_coordinates(key: str, parts: list[str], records: ObjRecords) -> None:
    """Add a ``v`` (three numbers) or ``vt`` (u and optional v, missing v = 0) line to ``records``.

    Raises:
        ValueError: for an unreadable number or a ``v`` with fewer than three.
    """
    if key == "v":
        xyz = [float(x) for x in parts[1:4]]
        if len(xyz) != 3:
            raise ValueError(key)
        records.verts.append(xyz)
    else:
        uv = [float(x) for x in parts[1:3]]
        records.uvs.append(uv + [0.0] * (2 - len(uv)))


def parse_face(parts: list[str], records: ObjRecords, path: Path, number: int) -> None:
    """Add an ``f`` line to ``records`` as a triangle fan, in the current material; UVs when every corner has one.

    Raises:
        AffnerfError: naming the file and line, for an unreadable or out-of-range index.
    """
    corners = [c.split("/") for c in parts[1:]]
    if len(corners) < 3:
        logger.warning("%s: line %d: face with fewer than 3 corners; skipped", path, number)
        return
    vi = [_index(c[0], len(records.verts), path, number) for c in corners]
    has_uv = all(len(c) > 1 and c[1] for c in corners)
    ti = [_index(c[1], len(records.uvs), path, number) for c in corners] if has_uv else None
    mat = records.used.setdefault(records.current, len(records.used))
    for k in range(1, len(corners) - 1):
        records.faces.append([vi[0], vi[k], vi[k + 1]])
        records.face_uv.append(None if ti is None else [ti[0], ti[k], ti[k + 1]])
        records.face_material.append(mat)


def parse_mtllib(
    line: str, parts: list[str], records: ObjRecords, path: Path, textures: dict[Path, np.ndarray | None]
) -> None:
    """Read the MTL file(s) of an ``mtllib`` line into ``records.library``: the whole rest of the line when such a
    file exists (names with spaces), else each word."""
    name = line.strip()[len("mtllib") :].strip()
    names = [name] if (path.parent / name).is_file() else parts[1:]
    for n in names:
        records.library.update(read_mtl(path.parent / n, textures))


def parse_obj_lines(lines: list[str], path: Path, textures: dict[Path, np.ndarray | None]) -> ObjRecords:
    """The records of an OBJ file's lines (``v``, ``vt``, ``f``, ``usemtl``, ``mtllib``; others ignored).

    Raises:
        AffnerfError: naming the file and line, for an unreadable number or index, or an index out of range.
    """
    records = ObjRecords()
    for number, line in enumerate(lines, start=1):
        parts = line.split()
        if not parts:
            continue
        key = parts[0]
        if key in ("v", "vt"):
            try:
                parse_coordinates(key, parts, records)
            except ValueError:
                raise input_error(path, f"line {number}: unreadable {key!r} line {line.strip()[:40]!r}") from None
        elif key == "f":
            parse_face(parts, records, path, number)
        elif key == "usemtl":
            records.current = " ".join(parts[1:])
        elif key == "mtllib":
            parse_mtllib(line, parts, records, path, textures)
    return records


def corner_uvs(face_uv: list[list[int] | None], uvs: list[list[float]]) -> np.ndarray | None:
    """(F, 3, 2) UV of every face corner (zeros for faces without ``vt``), or ``None`` when no face has any."""
    if all(t is None for t in face_uv):
        return None
    t_idx = np.array([[-1, -1, -1] if t is None else t for t in face_uv], np.int64)  # (F, 3)
    return np.where(t_idx[..., None] >= 0, np.asarray(uvs, np.float64)[np.maximum(t_idx, 0)], 0.0)


def used_materials(records: ObjRecords, path: Path) -> tuple[Material, ...]:
    """The materials the faces use, in order of first use; an undefined name gets the default with a warning."""
    materials = []
    for name in records.used:
        if name and name not in records.library:
            logger.warning("%s: material %r is not defined; using the default", path, name)
        materials.append(records.library.get(name, DEFAULT_MATERIAL))
    return tuple(materials)


def obj_mesh(records: ObjRecords, path: Path) -> ObjMesh:
    """The mesh of an OBJ file's records, keeping only the vertices some face uses.

    Raises:
        AffnerfError: naming the file, when it has no faces or a non-finite vertex.
    """
    if not records.faces:
        raise input_error(path, "no faces")
    vertices = np.asarray(records.verts, np.float64)
    if not np.isfinite(vertices).all():
        raise input_error(path, "non-finite vertex coordinates")
    kept, inverse = np.unique(np.asarray(records.faces, np.int64).reshape(-1), return_inverse=True)
    face_uv = corner_uvs(records.face_uv, records.uvs)
    return ObjMesh(
        vertices=vertices[kept],
        faces=inverse.reshape(-1, 3).astype(np.int64),
        face_uv=face_uv,
        face_material=np.asarray(records.face_material, np.int32),
        materials=used_materials(records, path),
    )


def read_obj(path: Path, textures: dict[Path, np.ndarray | None] | None = None) -> ObjMesh:
    """Read an OBJ file with its MTL materials.

    Args:
        path: the ``.obj`` file.
        textures: cache of loaded texture images shared between files (a fresh one when ``None``).

    Returns:
        The mesh; faces in file order, polygons fan-triangulated.

    Raises:
        AffnerfError: naming the file, when it is missing or unreadable, has no faces, an unreadable number, an
            index out of range, or a non-finite vertex.
    """
    path = Path(path)
    lines = read_lines(path)
    records = parse_obj_lines(lines, path, {} if textures is None else textures)
    return obj_mesh(records, path)
