"""Load a PartNet-Mobility object folder as a part-annotated :class:`~affnerf.objects.asset.ObjectAsset`.

A folder holds ``mobility.urdf`` (links, their OBJ visuals and the joints), ``result.json`` (the part hierarchy;
leaves name their OBJs), ``meta.json`` (``model_cat``) and ``textured_objs/`` (OBJ + MTL, textures in
``images/``). Each URDF visual is placed by its link's world pose for the chosen joint state and given to the
hierarchy leaf that lists its OBJ; each leaf with geometry becomes one part, its affordance from the mapping
table (:mod:`affnerf.data.partnet.mapping`). The object is then normalised into the canonical cube.
"""

from __future__ import annotations

import logging
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from affnerf.data.partnet.hierarchy import Leaf, read_leaves, read_model_cat
from affnerf.data.partnet.kinematics import (
    MOVING_TYPES,
    descendant_links,
    joint_limits,
    joint_values,
    link_poses,
)
from affnerf.data.partnet.mapping import CategoryMapping, category_mapping, leaf_affordance, load_mapping
from affnerf.data.partnet.objfile import ObjMesh, read_obj
from affnerf.data.partnet.twosided import drop_back_copies
from affnerf.data.partnet.urdf import Urdf, parse_urdf
from affnerf.errors import input_error
from affnerf.objects.asset import JointState, Material, ObjectAsset, Part, canonicalize

logger = logging.getLogger(__name__)

#: ``ObjectAsset.source`` of imported objects.
SOURCE = "partnet-mobility"


@dataclass(frozen=True)
class Piece:
    """One placed OBJ of a leaf: the mesh, its (4, 4) world pose, and the link it hangs on."""

    mesh: ObjMesh
    pose: np.ndarray
    link: str


def part_names(leaves: list[Leaf]) -> dict[int, str]:
    """Unique part names: a leaf's name where no other leaf shares it, else ``<name>_<leaf id>``.

    Example:
        >>> part_names([Leaf(8, "handle", (), ()), Leaf(15, "handle", (), ()), Leaf(4, "shelf", (), ())])
        {8: 'handle_8', 15: 'handle_15', 4: 'shelf'}
    """
    counts = Counter(leaf.name for leaf in leaves)
    return {leaf.id: leaf.name if counts[leaf.name] == 1 else f"{leaf.name}_{leaf.id}" for leaf in leaves}


def obj_owners(leaves: list[Leaf], result_path: Path) -> dict[str, Leaf]:
    """``{OBJ stem: leaf}`` from the leaves' ``objs``; an OBJ listed by two leaves stays with the first (warning)."""
    owner: dict[str, Leaf] = {}
    for leaf in leaves:
        for stem in leaf.objs:
            if stem in owner:
                logger.warning(
                    "%s: %s is listed by leaves %d and %d; kept in the first",
                    result_path,
                    stem,
                    owner[stem].id,
                    leaf.id,
                )
            else:
                owner[stem] = leaf
    return owner


def place_visuals(
    src: Path, urdf: Urdf, poses: dict[str, np.ndarray], owner: dict[str, Leaf]
) -> dict[int, list[Piece]]:
    """Read every visual's OBJ (one face of each doubled pair kept, see :mod:`.twosided`) and pose it, grouped by
    the leaf that lists it.

    Args:
        src: the object folder (visual file names are relative to it).
        urdf: the parsed ``mobility.urdf``.
        poses: world (4, 4) pose per link.
        owner: leaf per OBJ stem (see :func:`obj_owners`); visuals no leaf lists are skipped with a warning.

    Returns:
        ``{leaf id: [Piece, ...]}`` in URDF order.

    Raises:
        AffnerfError: naming the OBJ file, when it is missing or broken (see :func:`read_obj`).
    """
    textures: dict[Path, np.ndarray | None] = {}
    meshes: dict[Path, ObjMesh] = {}
    out: dict[int, list[Piece]] = {}
    for link in urdf.links.values():
        for visual in link.visuals:
            path = src / visual.filename.removeprefix("package://")
            leaf = owner.get(path.stem)
            if leaf is None:
                logger.warning(
                    "%s: %s (link %r) is in no leaf of result.json; skipped", urdf.path, path.name, link.name
                )
                continue
            if path not in meshes:
                meshes[path] = drop_back_copies(read_obj(path, textures))
            pose = poses[link.name] @ visual.origin @ np.diag([*visual.scale, 1.0])
            out.setdefault(leaf.id, []).append(Piece(meshes[path], pose, link.name))
    return out


def _material_key(material: Material) -> tuple[object, ...]:
    """Identity of a material for merging: its fields, with the texture by object identity (images are cached)."""
    return (material.color, material.pattern, material.color2, material.period, material.axis, id(material.texture))


def build_part(name: str, affordance: str, pieces: list[Piece]) -> Part:
    """One part from placed OBJs: vertices transformed, faces offset, equal materials merged.

    Returns:
        A :class:`Part` whose ``face_uv`` is (F, 3, 2) when any piece has UVs (zeros elsewhere), else ``None``.
    """
    vertices, faces, uvs, mats = [], [], [], []
    materials: list[Material] = []
    index: dict[tuple[object, ...], int] = {}
    offset = 0
    for piece in pieces:
        m = piece.mesh
        vertices.append(m.vertices @ piece.pose[:3, :3].T + piece.pose[:3, 3])
        faces.append(m.faces + offset)
        offset += len(m.vertices)
        uvs.append(np.zeros((len(m.faces), 3, 2)) if m.face_uv is None else m.face_uv)
        remap = []
        for mat in m.materials:
            key = _material_key(mat)
            if key not in index:
                index[key] = len(materials)
                materials.append(mat)
            remap.append(index[key])
        mats.append(np.asarray(remap, np.int32)[m.face_material])
    mesh = trimesh.Trimesh(vertices=np.concatenate(vertices), faces=np.concatenate(faces), process=False)
    textured = any(p.mesh.face_uv is not None for p in pieces)
    return Part(
        name=name,
        affordance=affordance,
        mesh=mesh,
        materials=tuple(materials),
        face_material=np.concatenate(mats),
        face_uv=np.concatenate(uvs).astype(np.float32) if textured else None,
    )


def joint_states(urdf: Urdf, values: dict[str, float], part_links: dict[str, set[str]]) -> list[JointState]:
    """The state of every moving joint, with the parts on its child link and the links below it.

    Args:
        urdf: the parsed file.
        values: joint values by name.
        part_links: ``{part name: links its pieces hang on}``, in part order.
    """
    states = []
    for joint in urdf.joints:
        if joint.type not in MOVING_TYPES:
            continue
        moved = descendant_links(urdf, joint.child)
        lower, upper = joint_limits(joint)
        states.append(
            JointState(
                name=joint.name,
                type=joint.type,  # type: ignore[arg-type]
                value=values[joint.name],
                lower=lower,
                upper=upper,
                parts=tuple(name for name, links in part_links.items() if links & moved),
            )
        )
    return states


def load_partnet_object(
    src: Path,
    joint_state: str = "rest",
    rng: np.random.Generator | None = None,
    mapping: Path | None = None,
    strict: bool = False,
) -> ObjectAsset:
    """Load a PartNet-Mobility object folder as a part-annotated object in the canonical frame.

    Args:
        src: the object folder (``mobility.urdf``, ``result.json``, ``meta.json``, ``textured_objs/``).
        joint_state: ``rest`` (every joint at 0 clamped into its limits: the pose as modelled) or ``random``
            (uniform within the limits; continuous joints in [0, 2 pi)).
        rng: the generator ``random`` draws from.
        mapping: a user mapping YAML merged over the shipped table (see :func:`load_mapping`).
        strict: make a leaf that the mapping does not name an error instead of a warning.

    Returns:
        An asset with one part per hierarchy leaf that has geometry (named by :func:`part_names`), the states of
        the revolute, prismatic and continuous joints, ``source="partnet-mobility"``, ``params`` =
        ``{"partnet_id", "model_cat", "joint_state"}``, centred and scaled into the canonical cube (``scale``).

    Raises:
        AffnerfError: one line naming the file at fault: a missing or malformed ``meta.json``, ``result.json``,
            ``mobility.urdf`` or OBJ, a ``model_cat`` without mapping, an unmapped leaf with ``strict``, a bad
            mapping file.
    """
    src = Path(src)
    if not src.is_dir():
        raise input_error(src, "not a folder")
    model_cat = read_model_cat(src / "meta.json")
    entry = category_mapping(load_mapping(mapping), model_cat, src / "meta.json")
    leaves = read_leaves(src / "result.json")
    urdf = parse_urdf(src / "mobility.urdf")
    values = joint_values(urdf, joint_state, rng)
    poses = turned_link_poses(urdf, values, entry.yaw_deg)
    pieces = place_visuals(src, urdf, poses, obj_owners(leaves, src / "result.json"))
    parts, part_links = build_parts(src, leaves, pieces, entry, strict)
    asset = ObjectAsset(
        category=entry.category,
        parts=parts,
        params={"partnet_id": src.resolve().name, "model_cat": model_cat, "joint_state": joint_state},
        joints=joint_states(urdf, values, part_links),
        source=SOURCE,
    )
    return canonicalize(asset)


def turned_link_poses(urdf: Urdf, values: dict[str, float], yaw_deg: float) -> dict[str, np.ndarray]:
    """(4, 4) world pose of every link for the joint ``values``, turned by ``yaw_deg`` about +z (the category's
    front onto the canonical front)."""
    yaw = trimesh.transformations.rotation_matrix(np.radians(yaw_deg), [0.0, 0.0, 1.0])
    return {name: yaw @ pose for name, pose in link_poses(urdf, values).items()}


def leaves_with_geometry(
    leaves: list[Leaf], pieces: dict[int, list[Piece]], result_path: Path, urdf_name: str
) -> list[Leaf]:
    """The leaves that have placed pieces, in order; each other leaf is skipped with a warning."""
    for leaf in leaves:
        if leaf.id not in pieces:
            logger.warning(
                "%s: leaf %d (%s) has no geometry in %s; skipped", result_path, leaf.id, leaf.name, urdf_name
            )
    return [leaf for leaf in leaves if leaf.id in pieces]


def build_parts(
    src: Path, leaves: list[Leaf], pieces: dict[int, list[Piece]], entry: CategoryMapping, strict: bool
) -> tuple[list[Part], dict[str, set[str]]]:
    """One part per leaf with geometry, named by :func:`part_names`, its affordance from the mapping.

    Returns:
        The parts, and ``{part name: links its pieces hang on}`` (for :func:`joint_states`).

    Raises:
        AffnerfError: naming ``src`` when no leaf has geometry; naming ``result.json`` for an unmapped leaf with
            ``strict``.
    """
    result_path = src / "result.json"
    with_geometry = leaves_with_geometry(leaves, pieces, result_path, "mobility.urdf")
    names = part_names(with_geometry)
    parts = [
        build_part(names[leaf.id], leaf_affordance(leaf, entry, result_path, names[leaf.id], strict), pieces[leaf.id])
        for leaf in with_geometry
    ]
    if not parts:
        raise input_error(src, "no part geometry (no URDF visual is listed in result.json)")
    return parts, {names[leaf.id]: {p.link for p in pieces[leaf.id]} for leaf in with_geometry}
