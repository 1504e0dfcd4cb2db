"""Where two predictions of one object agree on its labels.

AFF-NeRF predicts an object twice on the way to its affordance model: from the encoder's codes, then from the
codes fitted to the input view (:mod:`affnerf.predict.invert`). Where both put the same label at the same place
the label is more likely right (benchmarks/results/grasp_margin.md, "Agreement of two predictions"). A fitted
prediction's mesh carries this as the face property ``confirmed`` (conventions §8), and the grasp planner tries
the confirmed faces of a task part first (:func:`affnerf.grasp.planner.plan_grasps`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.spatial import cKDTree

from affnerf.meshio import LabelledMesh

#: Default ``distance`` of :func:`agreeing_faces` in the canonical frame, metres (objects are about 0.44 long there).
#: Chosen on validation objects: benchmarks/results/grasp_margin.md.
AGREEMENT_DISTANCE = 0.01


def agreeing_faces(
    vertices: np.ndarray,
    faces: np.ndarray,
    labels: np.ndarray,
    other_vertices: np.ndarray,
    other_faces: np.ndarray,
    other_labels: np.ndarray,
    distance: float = AGREEMENT_DISTANCE,
) -> np.ndarray:
    """Which faces of a labelled mesh another labelled mesh of the same object confirms: the face of the other
    mesh whose centre is nearest this face's centre lies within ``distance`` and carries the same label.

    Args:
        vertices: (V, 3); faces: (F, 3); labels: (F,) the mesh's face labels.
        other_vertices: (V', 3); other_faces: (F', 3); other_labels: (F',) the other mesh's, in the same frame.
        distance: largest gap between the two centres, in the vertices' units.

    Returns:
        (F,) bool; all False when the other mesh has no faces.

    Example:
        >>> tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> agreeing_faces(tri, np.array([[0, 1, 2]]), np.array([1]), tri, np.array([[0, 1, 2]]), np.array([1]))
        array([ True])
    """
    if not len(other_faces) or not len(faces):
        return np.zeros(len(faces), bool)
    centres = np.asarray(vertices)[faces].mean(axis=1)
    gap, nearest = cKDTree(np.asarray(other_vertices)[other_faces].mean(axis=1)).query(centres)
    return (gap <= distance) & (np.asarray(other_labels)[nearest] == np.asarray(labels))


def confirmed(mesh: LabelledMesh, other: LabelledMesh, distance: float = AGREEMENT_DISTANCE) -> LabelledMesh:
    """``mesh`` with the face property ``confirmed`` (F,) uint8: 1 where ``other``, a second prediction of the
    object in the same frame, confirms the face's ``affordance`` label (:func:`agreeing_faces`). Both meshes need
    the face property ``affordance``; a mesh without faces is returned as it is."""
    if not len(mesh.faces):
        return mesh
    agrees = agreeing_faces(
        mesh.vertices,
        mesh.faces,
        mesh.face_props["affordance"],
        other.vertices,
        other.faces,
        other.face_props["affordance"],
        distance,
    )
    return replace(mesh, face_props={**mesh.face_props, "confirmed": agrees.astype(np.uint8)})
