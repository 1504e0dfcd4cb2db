"""Agreement of two predictions' labels: which faces a second labelled mesh of the object confirms."""

from __future__ import annotations

import numpy as np

from affnerf.grasp.size import scaled
from affnerf.grasp.target import GraspObject
from affnerf.meshio import LabelledMesh, read_labelled_ply, write_labelled_ply
from affnerf.predict.agreement import agreeing_faces, confirmed


def _strip(n: int = 21, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A flat strip 0.4 long along x of 2 (n - 1) triangles, lifted by ``offset`` along z."""
    x = np.linspace(-0.2, 0.2, n)
    row = np.stack([x, np.zeros(n), np.full(n, offset)], 1)
    vertices = np.concatenate([row, row + [0.0, 0.02, 0.0]])
    faces = np.concatenate([[[i, i + 1, n + i], [i + 1, n + i + 1, n + i]] for i in range(n - 1)])
    return vertices, faces


def test_faces_are_confirmed_where_the_other_mesh_has_the_same_label_nearby():
    vertices, faces = _strip()
    centre_x = vertices[faces].mean(axis=1)[:, 0]
    labels = np.where(centre_x < 0, 1, 3)
    other_labels = np.where(centre_x < 0.1, 1, 3)  # the other prediction puts label 1 further along x
    agrees = agreeing_faces(vertices, faces, labels, vertices + [0, 0, 0.005], faces, other_labels, 0.01)
    assert np.array_equal(agrees, ~((centre_x > 0) & (centre_x < 0.1)))


def test_nothing_is_confirmed_by_a_mesh_too_far_away_or_without_faces():
    vertices, faces = _strip()
    labels = np.ones(len(faces), int)
    far, _ = _strip(offset=0.05)
    assert not agreeing_faces(vertices, faces, labels, far, faces, labels, 0.01).any()
    assert agreeing_faces(vertices, faces, labels, far, faces, labels, 0.1).all()
    none = agreeing_faces(vertices, faces, labels, np.zeros((0, 3)), np.zeros((0, 3), int), np.zeros(0, int))
    assert none.shape == (len(faces),) and not none.any()


def test_scaling_an_object_keeps_its_agreement():
    vertices, faces = _strip()
    agrees = np.arange(len(faces)) % 2 == 0
    obj = GraspObject(vertices, faces, np.ones(len(faces), int), "strip", agrees)
    assert np.array_equal(scaled(obj, 0.5).face_agrees, agrees)


def test_a_confirmed_mesh_carries_the_agreement_to_the_grasp_planner(tmp_path):
    vertices, faces = _strip()
    centre_x = vertices[faces].mean(axis=1)[:, 0]
    mesh = LabelledMesh(vertices, faces, face_props={"affordance": np.where(centre_x < 0, 1, 3).astype(np.uint8)})
    other = LabelledMesh(vertices, faces, face_props={"affordance": np.ones(len(faces), np.uint8)})
    marked = confirmed(mesh, other, 0.01)
    assert np.array_equal(marked.face_props["confirmed"], (centre_x < 0).astype(np.uint8))
    assert "confirmed" not in mesh.face_props  # the input is left as it was
    write_labelled_ply(tmp_path / "m.ply", marked)
    obj = GraspObject.from_mesh(read_labelled_ply(tmp_path / "m.ply"))
    assert np.array_equal(obj.face_agrees, centre_x < 0)
    assert GraspObject.from_mesh(mesh).face_agrees is None
