"""A tiny PartNet-Mobility-format object built by code, for tests and examples.

A toy ``StorageFurniture`` made of boxes, modelled like the real files: y up and the front towards +z in the
mesh files, a fixed base joint with ``rpy = (pi/2, 0, -pi/2)`` turning that z-up, a door on a revolute joint
(hinge on its right edge, opening outwards) and a drawer on a prismatic joint (sliding along +z), each with a
handle. The door panel's OBJ has two materials, its front textured by ``images/texture_0.png`` through UVs and
the other sides plain, with faces without ``vt`` as in real files. ``result.json`` nests the frame body as
``cabinet_frame/other/other_leaf``, so its affordance is found only through an ancestor; two leaves are named
``handle``. With ``doubled_faces`` every face is written twice as in real files, the extra copy in the opposite
winding and a plain white material (``material_back``), listed before the face it backs.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

#: The base joint's rpy in PartNet-Mobility files: mesh y-up onto URDF z-up.
BASE_RPY = "1.570796326794897 0 -1.570796326794897"
#: Door hinge (joint origin) in the mesh frame: the door's right edge at the front.
HINGE = (0.3, 0.0, 0.2)
#: Limits of the door (radians) and drawer (metres).
DOOR_LIMITS = (0.0, np.pi / 2)
DRAWER_LIMITS = (0.0, 0.3)


@dataclass(frozen=True)
class _Box:
    """An axis-aligned box OBJ: stem, corners (mesh frame), colour, and whether its +z side is textured."""

    stem: str
    lo: tuple[float, float, float]
    hi: tuple[float, float, float]
    color: tuple[float, float, float]
    textured_front: bool = False


_BOXES = (
    _Box("original-1", (-0.3, 0.0, -0.2), (0.3, 0.8, 0.18), (0.55, 0.4, 0.25)),  # frame body: other_leaf
    _Box("original-2", (-0.3, 0.0, -0.22), (0.3, 0.8, -0.2), (0.5, 0.35, 0.2)),  # back_panel
    _Box("original-3", (-0.3, 0.35, 0.18), (0.3, 0.8, 0.2), (1.0, 1.0, 1.0), textured_front=True),  # door
    _Box("original-4", (-0.26, 0.5, 0.2), (-0.22, 0.65, 0.24), (0.8, 0.8, 0.85)),  # door handle
    _Box("original-5", (-0.3, 0.02, 0.18), (0.3, 0.33, 0.2), (0.6, 0.45, 0.3)),  # drawer front
    _Box("original-6", (-0.28, 0.03, -0.15), (0.28, 0.05, 0.18), (0.6, 0.45, 0.3)),  # drawer bottom
    _Box("original-7", (-0.05, 0.15, 0.2), (0.05, 0.2, 0.24), (0.8, 0.8, 0.85)),  # drawer handle
)

#: URDF links: name -> (OBJ stems, visual origin xyz).
_LINKS = {
    "link_0": (("original-3", "original-4"), tuple(-c for c in HINGE)),
    "link_1": (("original-5", "original-6", "original-7"), (0.0, 0.0, 0.0)),
    "link_2": (("original-1", "original-2"), (0.0, 0.0, 0.0)),
}


def _box_sides(lo: np.ndarray, hi: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """The six sides of a box as (name, (4, 3) corners counter-clockwise seen from outside)."""
    sides = []
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        for sign, level in ((-1, lo[a]), (1, hi[a])):
            bits = [(0, 0), (1, 0), (1, 1), (0, 1)] if sign > 0 else [(0, 0), (0, 1), (1, 1), (1, 0)]
            quad = np.zeros((4, 3))
            for k, (ub, uc) in enumerate(bits):
                quad[k, a] = level
                quad[k, b] = hi[b] if ub else lo[b]
                quad[k, c] = hi[c] if uc else lo[c]
            sides.append(("+-"[sign < 0] + "xyz"[a], quad))
    return sides


def back_copies(faces: list[str]) -> list[str]:
    """``f`` lines of the same faces in the opposite winding, without ``vt``, in the white ``material_back``.

    Example:
        >>> back_copies(["f 1/1 2/2 3/3"])
        ['usemtl material_back', 'f 3 2 1']
    """
    reversed_faces = [" ".join(["f", *(c.split("/")[0] for c in line.split()[:0:-1])]) for line in faces]
    return ["usemtl material_back", *reversed_faces]


def box_obj_text(box: _Box, nan_vertex: bool = False, doubled: bool = False) -> str:
    """The OBJ text of a box: 4 vertices per side; the +z side textured (``vt``) when ``box.textured_front``.

    Args:
        box: the box.
        nan_vertex: write the first vertex as ``nan`` (a broken file for tests).
        doubled: write every face a second time, first, in the opposite winding (see :func:`back_copies`).
    """
    lines = [f"# affnerf PartNet-Mobility fixture: {box.stem}", f"mtllib {box.stem}.mtl", f"o {box.stem}"]
    sides = _box_sides(np.asarray(box.lo), np.asarray(box.hi))
    for _, quad in sides:
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in quad]
    if nan_vertex:
        lines[3] = "v nan 0 0"
    lines += ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1"]
    if doubled:
        faces = [f"f {4 * s + 1} {4 * s + 2} {4 * s + 3}" for s in range(len(sides))]
        faces += [f"f {4 * s + 1} {4 * s + 3} {4 * s + 4}" for s in range(len(sides))]
        lines += back_copies(faces)
    plain = []
    for s, (name, _) in enumerate(sides):
        v = 4 * s + 1
        if box.textured_front and name == "+z":
            # u runs along +x, v along +y (up): the image stands upright on the door's front
            lines += ["usemtl material_0_0", f"f {v}/1 {v + 1}/2 {v + 2}/3", f"f {v}/1 {v + 2}/3 {v + 3}/4"]
        else:
            plain += [f"f {v} {v + 1} {v + 2}", f"f {v} {v + 2} {v + 3}"]
    lines += ["usemtl material_1_0" if box.textured_front else "usemtl material_0_0", *plain]
    return "\n".join(lines) + "\n"


def box_mtl_text(box: _Box, doubled: bool = False) -> str:
    """The MTL text of a box: ``material_0_0`` (textured when ``box.textured_front``) and ``material_1_0``, and
    with ``doubled`` the white ``material_back`` of the back copies."""
    kd = " ".join(f"{c:.4f}" for c in box.color)
    first = ["newmtl material_0_0", f"Kd {kd}"]
    if box.textured_front:
        first = ["newmtl material_0_0", "Kd 1 1 1", "map_Kd ../images/texture_0.png"]
    back = ["newmtl material_back", "Kd 1 1 1", ""] if doubled else []
    return "\n".join([*first, "", "newmtl material_1_0", f"Kd {kd}", "", *back])


def fixture_texture() -> np.ndarray:
    """(8, 8, 3) uint8 texture: a 2x2-cell checker of two woods, the top row red (to see which way is up)."""
    cells = (np.add.outer(np.arange(8) // 4, np.arange(8) // 4) % 2).astype(bool)
    img = np.where(cells[..., None], np.array([200, 160, 110], np.uint8), np.array([120, 80, 40], np.uint8))
    img[0] = (220, 30, 30)
    return img.astype(np.uint8)


def urdf_text(malformed_limit: bool = False) -> str:
    """The ``mobility.urdf`` text; ``malformed_limit`` writes the drawer's lower limit as ``-z0.008``."""
    hinge = " ".join(str(c) for c in HINGE)
    lines = ['<?xml version="1.0" ?>', '<robot name="partnet_affnerf_fixture">', '\t<link name="base"/>']
    for link, (stems, xyz) in _LINKS.items():
        lines.append(f'\t<link name="{link}">')
        for stem in stems:
            origin = " ".join(str(c) for c in xyz)
            lines += [
                f'\t\t<visual name="{stem}">',
                f'\t\t\t<origin xyz="{origin}"/>',
                f'\t\t\t<geometry><mesh filename="textured_objs/{stem}.obj"/></geometry>',
                "\t\t</visual>",
            ]
        lines.append("\t</link>")
    lower = "-z0.008" if malformed_limit else str(DRAWER_LIMITS[0])
    lines += [
        '\t<joint name="joint_0" type="revolute">',
        f'\t\t<origin xyz="{hinge}"/>',
        '\t\t<axis xyz="0 1 0"/>',
        '\t\t<child link="link_0"/>',
        '\t\t<parent link="link_2"/>',
        f'\t\t<limit lower="{DOOR_LIMITS[0]}" upper="{DOOR_LIMITS[1]}"/>',
        "\t</joint>",
        '\t<joint name="joint_1" type="prismatic">',
        '\t\t<origin xyz="0 0 0"/>',
        '\t\t<axis xyz="0 0 1"/>',
        '\t\t<child link="link_1"/>',
        '\t\t<parent link="link_2"/>',
        f'\t\t<limit lower="{lower}" upper="{DRAWER_LIMITS[1]}"/>',
        "\t</joint>",
        '\t<joint name="joint_2" type="fixed">',
        f'\t\t<origin rpy="{BASE_RPY}" xyz="0 0 0"/>',
        '\t\t<child link="link_2"/>',
        '\t\t<parent link="base"/>',
        "\t</joint>",
        "</robot>",
    ]
    return "\n".join(lines) + "\n"


def _node(id_: int, name: str, children: list | None = None, objs: list[str] | None = None) -> dict:
    node: dict = {"text": name.replace("_", " ").capitalize(), "id": id_, "name": name}
    if children is not None:
        node["children"] = children
    if objs is not None:
        node["objs"] = objs
    return node


def result_tree() -> list[dict]:
    """The ``result.json`` hierarchy (leaves list the OBJ stems)."""
    frame = _node(
        2,
        "cabinet_frame",
        [
            _node(3, "other", [_node(4, "other_leaf", objs=["original-1"])]),
            _node(5, "back_panel", objs=["original-2"]),
        ],
    )
    door = _node(
        6,
        "cabinet_door",
        [
            _node(7, "cabinet_door_surface", objs=["original-3"]),
            _node(8, "handle", objs=["original-4"]),
        ],
    )
    drawer = _node(
        9,
        "drawer",
        [
            _node(
                10,
                "drawer_box",
                [
                    _node(11, "drawer_front", objs=["original-5"]),
                    _node(12, "drawer_bottom", objs=["original-6"]),
                ],
            ),
            _node(13, "handle", objs=["original-7"]),
        ],
    )
    return [_node(0, "storage_furniture", [_node(1, "cabinet", [frame, door, drawer])])]


def write_partnet_fixture(
    dest: Path,
    model_cat: str = "StorageFurniture",
    malformed_limit: bool = False,
    missing_obj: bool = False,
    nonfinite_vertex: bool = False,
    doubled_faces: bool = False,
) -> Path:
    """Write the toy cabinet as a PartNet-Mobility object folder.

    Args:
        dest: the folder to create (parents too); its name plays the PartNet id.
        model_cat: ``meta.json``'s ``model_cat`` (e.g. an unknown one for tests).
        malformed_limit: write the drawer's lower limit as ``-z0.008`` (read as -0.008 with a warning).
        missing_obj: leave out ``textured_objs/original-7.obj`` (the drawer handle).
        nonfinite_vertex: write a ``nan`` vertex into ``textured_objs/original-1.obj``.
        doubled_faces: write every face twice, the extra copy white and in the opposite winding (real files do).

    Returns:
        ``dest``, holding ``mobility.urdf``, ``result.json``, ``meta.json``, ``textured_objs/*.obj|mtl`` and
        ``images/texture_0.png``.
    """
    dest = Path(dest)
    (dest / "textured_objs").mkdir(parents=True, exist_ok=True)
    (dest / "images").mkdir(exist_ok=True)
    Image.fromarray(fixture_texture()).save(dest / "images" / "texture_0.png")
    for box in _BOXES:
        if missing_obj and box.stem == "original-7":
            continue
        obj = box_obj_text(box, nan_vertex=nonfinite_vertex and box.stem == "original-1", doubled=doubled_faces)
        (dest / "textured_objs" / f"{box.stem}.obj").write_text(obj)
        (dest / "textured_objs" / f"{box.stem}.mtl").write_text(box_mtl_text(box, doubled_faces))
    (dest / "mobility.urdf").write_text(urdf_text(malformed_limit))
    (dest / "result.json").write_text(json.dumps(result_tree(), indent=1))
    meta = {"model_id": "affnerf-fixture", "anno_id": dest.name, "version": "3", "model_cat": model_cat}
    (dest / "meta.json").write_text(json.dumps(meta))
    return dest
