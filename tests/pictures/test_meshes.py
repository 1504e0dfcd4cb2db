"""Pictures of meshes: the object is drawn in its affordance colours and the background stays white."""

from __future__ import annotations

import numpy as np
import trimesh

from affnerf.meshio import LabelledMesh
from affnerf.pictures.meshes import affordance_colors, coloured_surface, mesh_preview, views_around
from affnerf.vocab import AFFORDANCE_PALETTE


def _box_mesh(label: int) -> LabelledMesh:
    box = trimesh.creation.box((0.1, 0.1, 0.1))
    return LabelledMesh(
        np.asarray(box.vertices),
        np.asarray(box.faces),
        face_props={"affordance": np.full(len(box.faces), label, np.uint8)},
    )


def test_mesh_preview_shows_the_class_colour_on_white():
    picture = mesh_preview(_box_mesh(1), size=64, yaws=(0.0, 90.0))
    assert picture.shape == (64, 128, 3) and picture.dtype == np.uint8
    assert (picture[0, 0] == 255).all()  # corner: background
    centre = picture[32, 32].astype(float)
    red = AFFORDANCE_PALETTE[1].astype(float)  # grasp is red-dominant
    assert centre.argmax() == red.argmax() and not (centre == 255).all()


def test_an_empty_mesh_gives_a_blank_picture():
    empty = LabelledMesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    assert (mesh_preview(empty, size=16) == 255).all()


def test_coloured_surface_keeps_one_material_per_distinct_colour():
    colors = affordance_colors(np.array([1, 1, 2, 2]))
    surface = coloured_surface(np.eye(3), np.array([[0, 1, 2]] * 4), colors)
    assert len(surface.materials) == 2
    assert surface.face_material.tolist() in ([0, 0, 1, 1], [1, 1, 0, 0])
    picture = views_around(surface, np.zeros(3), 1.0, (0.0,), 16)
    assert picture.shape == (16, 16, 3)
