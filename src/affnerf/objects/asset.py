"""Part-annotated objects: parts with meshes, affordances and materials, in the canonical frame (conventions §1, §3).

An :class:`ObjectAsset` is what every object source produces (the procedural families and the PartNet-Mobility
importer) and what the ray caster and dataset writer consume. Part ids are 1-based positions in ``parts``
(0 is background in every label map).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np
import trimesh

from affnerf.errors import AffnerfError
from affnerf.vocab import affordance_id

#: Half the side of the canonical cube: every object fits inside [-0.25, 0.25]^3 (conventions §1).
CANONICAL_HALF_EXTENT = 0.25

Pattern = Literal["plain", "stripes", "checker", "speckle"]


@dataclass(frozen=True)
class Material:
    """How a set of faces looks.

    Attributes:
        color: base albedo, RGB in [0, 1].
        pattern: a solid procedural texture evaluated at the 3D hit point in the object frame:
            ``plain`` (just ``color``), ``stripes`` (bands across ``axis``), ``checker`` (3D checker) or
            ``speckle`` (random cells mixing ``color`` and ``color2``).
        color2: the second colour of a pattern.
        period: the pattern's period in metres.
        axis: unit direction the stripes vary along.
        texture: optional (H, W, 3) uint8 image sampled at the hit point's UV (needs ``Part.face_uv``);
            multiplied by ``color`` as in an OBJ material's ``Kd`` with ``map_Kd``.
    """

    color: tuple[float, float, float] = (0.7, 0.7, 0.7)
    pattern: Pattern = "plain"
    color2: tuple[float, float, float] = (0.3, 0.3, 0.3)
    period: float = 0.02
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    texture: np.ndarray | None = field(default=None, compare=False, repr=False)


@dataclass
class Part:
    """One named part of an object.

    Attributes:
        name: part name, unique within the object (e.g. ``handle``, ``lens_left``).
        affordance: a name from the vocabulary (:mod:`affnerf.vocab`).
        mesh: the part's surface in the object frame, metres. Procedural parts are closed and
            consistently oriented; imported parts are whatever the source file holds.
        materials: the materials its faces use.
        face_material: (F,) index into ``materials`` per face; ``None`` means all faces use ``materials[0]``.
        face_uv: (F, 3, 2) texture coordinates per face corner, or ``None`` when untextured.
    """

    name: str
    affordance: str
    mesh: trimesh.Trimesh
    materials: tuple[Material, ...] = (Material(),)
    face_material: np.ndarray | None = None
    face_uv: np.ndarray | None = None

    def __post_init__(self) -> None:
        affordance_id(self.affordance)  # raises on a name outside the vocabulary
        n_faces = len(self.mesh.faces)
        if self.face_material is not None and self.face_material.shape != (n_faces,):
            raise AffnerfError(f"part {self.name!r}: face_material has shape {self.face_material.shape}")
        if self.face_uv is not None and self.face_uv.shape != (n_faces, 3, 2):
            raise AffnerfError(f"part {self.name!r}: face_uv has shape {self.face_uv.shape}")


@dataclass(frozen=True)
class JointState:
    """The state of one articulation joint, recorded in ``transforms.json``.

    Attributes:
        name: joint name (e.g. ``door_left``, ``drawer_0``).
        type: ``revolute`` (radians) or ``prismatic`` (metres).
        value: the state the object was built in.
        lower: lowest allowed value (closed, for doors and drawers).
        upper: highest allowed value.
        parts: names of the parts the joint moves.
    """

    name: str
    type: Literal["revolute", "prismatic", "continuous"]
    value: float
    lower: float
    upper: float
    parts: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict of this state."""
        return {
            "name": self.name,
            "type": self.type,
            "value": float(self.value),
            "limits": [float(self.lower), float(self.upper)],
            "parts": list(self.parts),
        }


@dataclass
class ObjectAsset:
    """A part-annotated object in its canonical frame.

    Attributes:
        category: category name (``screwdriver``, ``cabinet``, ...).
        parts: the parts; part id ``i + 1`` is ``parts[i]``.
        params: the shape, style and appearance parameters it was built from (JSON-ready), for the record.
        joints: articulation states (empty for rigid objects).
        scale: the uniform scale applied to bring the object into the canonical cube.
        source: ``procedural`` or ``partnet-mobility``.
    """

    category: str
    parts: list[Part]
    params: dict[str, Any] = field(default_factory=dict)
    joints: list[JointState] = field(default_factory=list)
    scale: float = 1.0
    source: str = "procedural"

    def __post_init__(self) -> None:
        if not self.parts:
            raise AffnerfError(f"{self.category} object has no parts")
        names = [p.name for p in self.parts]
        if len(set(names)) != len(names):
            raise AffnerfError(f"{self.category} object has repeated part names: {names}")
        if len(self.parts) > 255:
            raise AffnerfError(f"{self.category} object has {len(self.parts)} parts; at most 255 fit a label map")

    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned bounds (min, max) over all parts."""
        v = np.concatenate([p.mesh.vertices for p in self.parts])
        return np.stack([v.min(axis=0), v.max(axis=0)])

    def part_table(self) -> list[dict[str, Any]]:
        """The ``parts`` list of ``transforms.json``: ``[{"id", "name", "affordance"}, ...]``."""
        return [{"id": i + 1, "name": p.name, "affordance": p.affordance} for i, p in enumerate(self.parts)]


#: Largest side of an object's bounding box in the canonical frame: objects are normalised to it, as ShapeNet
#: objects are for pixelNeRF, so that every object uses the cube and appears at a similar size in the images.
NORMALISED_EXTENT = 0.44


def canonicalize(asset: ObjectAsset, extent: float = NORMALISED_EXTENT) -> ObjectAsset:
    """Centre the object's bounding box at the origin and scale it uniformly so its largest side is ``extent``.

    A single image cannot tell an object's absolute size, so every object is brought to one size, leaving its
    proportions alone; ``scale`` records the factor (canonical = source * scale), so metric size is recoverable.

    Args:
        asset: any object; its parts' meshes are not modified (copies are transformed).
        extent: the largest side of the bounding box afterwards; at most the cube's side (0.5 m).

    Returns:
        A new asset with ``scale`` multiplied by the applied factor.

    Example:
        >>> from affnerf.objects.primitives import box
        >>> a = canonicalize(ObjectAsset("toy", [Part("b", "grasp", box((0.1, 0.2, 0.4)))]))
        >>> a.bounds().round(3).tolist(), round(a.scale, 3)
        ([[-0.055, -0.11, -0.22], [0.055, 0.11, 0.22]], 1.1)
    """
    lo, hi = asset.bounds()
    centre = (lo + hi) / 2.0
    size = float(np.max(hi - lo))
    if not np.isfinite(size) or size <= 0:
        raise AffnerfError(f"{asset.category} object has degenerate or non-finite bounds")
    factor = extent / size
    matrix = np.eye(4)
    matrix[:3, :3] *= factor
    matrix[:3, 3] = -centre * factor
    parts = [replace(p, mesh=p.mesh.copy().apply_transform(matrix)) for p in asset.parts]
    return replace(asset, parts=parts, scale=asset.scale * factor)


@dataclass
class SurfaceMesh:
    """All parts of an object merged into one triangle soup with per-face attributes (what the ray caster reads).

    Attributes:
        vertices: (V, 3) float64 positions.
        faces: (F, 3) int64 vertex indices.
        face_part: (F,) uint8 part id (1-based).
        face_affordance: (F,) uint8 affordance id.
        face_material: (F,) int32 index into ``materials``.
        face_uv: (F, 3, 2) float32 texture coordinates (zeros where untextured).
        materials: all materials of all parts.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_part: np.ndarray
    face_affordance: np.ndarray
    face_material: np.ndarray
    face_uv: np.ndarray
    materials: list[Material]

    @property
    def vertex_part(self) -> np.ndarray:
        """(V,) uint8 part id per vertex (parts do not share vertices, so this is well defined)."""
        out = np.zeros(len(self.vertices), dtype=np.uint8)
        out[self.faces.reshape(-1)] = np.repeat(self.face_part, 3)
        return out

    @property
    def vertex_affordance(self) -> np.ndarray:
        """(V,) uint8 affordance id per vertex."""
        out = np.zeros(len(self.vertices), dtype=np.uint8)
        out[self.faces.reshape(-1)] = np.repeat(self.face_affordance, 3)
        return out


def merge_parts(asset: ObjectAsset) -> SurfaceMesh:
    """Merge an asset's parts into one :class:`SurfaceMesh`, keeping part, affordance and material per face."""
    vertices, faces, face_part, face_aff, face_mat, face_uv = [], [], [], [], [], []
    materials: list[Material] = []
    offset = 0
    for pid, part in enumerate(asset.parts, start=1):
        mesh = part.mesh
        n_faces = len(mesh.faces)
        vertices.append(np.asarray(mesh.vertices, dtype=np.float64))
        faces.append(np.asarray(mesh.faces, dtype=np.int64) + offset)
        offset += len(mesh.vertices)
        face_part.append(np.full(n_faces, pid, dtype=np.uint8))
        face_aff.append(np.full(n_faces, affordance_id(part.affordance), dtype=np.uint8))
        local = np.zeros(n_faces, dtype=np.int32) if part.face_material is None else part.face_material
        face_mat.append(np.asarray(local, dtype=np.int32) + len(materials))
        materials.extend(part.materials)
        uv = np.zeros((n_faces, 3, 2), np.float32) if part.face_uv is None else part.face_uv
        face_uv.append(np.asarray(uv, dtype=np.float32))
    surface = SurfaceMesh(
        vertices=np.concatenate(vertices),
        faces=np.concatenate(faces),
        face_part=np.concatenate(face_part),
        face_affordance=np.concatenate(face_aff),
        face_material=np.concatenate(face_mat),
        face_uv=np.concatenate(face_uv),
        materials=materials,
    )
    if not np.isfinite(surface.vertices).all():
        raise AffnerfError(f"{asset.category} object has non-finite vertices")
    if len(surface.faces) == 0:
        raise AffnerfError(f"{asset.category} object has no faces")
    return surface
