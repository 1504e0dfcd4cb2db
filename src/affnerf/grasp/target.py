"""The object to be grasped: a labelled mesh with what planning and scoring need (areas, normals, labels, a ray
caster, the torque reference)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from affnerf.data.raycast import RayCaster
from affnerf.errors import input_error
from affnerf.grasp.quality import object_radius
from affnerf.meshio import LabelledMesh, face_areas, majority_face_labels, read_labelled_ply, sample_surface_points
from affnerf.vocab import AFFORDANCE_CLASSES


@dataclass
class GraspObject:
    """A mesh to grasp, in metres.

    Attributes:
        vertices: (V, 3).
        faces: (F, 3).
        face_affordance: (F,) affordance ids, or None when the mesh carries no labels.
        name: where it came from (for messages).
        face_agrees: (F,) bool faces whose label a second prediction of the object confirms (the mesh's face
            property ``confirmed``, :func:`affnerf.predict.agreement.confirmed`; a task part is planned on those
            first), or None.
        face_confidence: (F,) how sure the predicting field is of each face's label, in [0, 1] (the mesh's face
            property ``confidence`` in percent, :func:`affnerf.predict.mesh.face_confidence`; a task part is
            planned first on the faces at least :attr:`~affnerf.grasp.planner.PlanConfig.min_confidence` sure),
            or None.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_affordance: np.ndarray | None = None
    name: str = "mesh"
    face_agrees: np.ndarray | None = None
    face_confidence: np.ndarray | None = None
    _caster: RayCaster | None = field(default=None, repr=False)

    @classmethod
    def from_mesh(cls, mesh: LabelledMesh, name: str = "mesh") -> GraspObject:
        """From a labelled mesh: per-face ``affordance`` if present, else the majority of its vertices'; the face
        properties ``confirmed`` and ``confidence`` (percent), when present, as :attr:`face_agrees` and
        :attr:`face_confidence`."""
        labels = mesh.face_props.get("affordance")
        if labels is None and "affordance" in mesh.vertex_props:
            labels = majority_face_labels(mesh.faces, np.asarray(mesh.vertex_props["affordance"]))
        agrees = mesh.face_props.get("confirmed")
        confidence = mesh.face_props.get("confidence")
        return cls(
            np.asarray(mesh.vertices, np.float64),
            np.asarray(mesh.faces, np.int64),
            None if labels is None else np.asarray(labels, np.int64),
            name,
            None if agrees is None else np.asarray(agrees) > 0,
            None if confidence is None else np.asarray(confidence, np.float64) / 100.0,
        )

    @property
    def caster(self) -> RayCaster:
        if self._caster is None:
            self._caster = RayCaster(self.vertices, self.faces)
        return self._caster

    @cached_property
    def face_areas(self) -> np.ndarray:
        """(F,) triangle areas in m^2."""
        return face_areas(self.vertices, self.faces)

    @cached_property
    def face_normals(self) -> np.ndarray:
        """(F, 3) unit outward normals (by winding)."""
        tri = self.vertices[self.faces]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-20)

    @cached_property
    def centroid(self) -> np.ndarray:
        """(3,) area-weighted centroid of the surface (the torque reference of the quality)."""
        centres = self.vertices[self.faces].mean(axis=1)
        return (centres * self.face_areas[:, None]).sum(0) / max(self.face_areas.sum(), 1e-20)

    @cached_property
    def radius(self) -> float:
        return object_radius(self.vertices, self.centroid)

    def label_names(self, faces: np.ndarray) -> list[str]:
        """Affordance names of faces (``unlabelled`` for a mesh without labels)."""
        if self.face_affordance is None:
            return ["unlabelled"] * len(faces)
        return [
            AFFORDANCE_CLASSES[int(c)] if 0 <= c < len(AFFORDANCE_CLASSES) else str(int(c))
            for c in self.face_affordance[faces]
        ]

    def sample_surface(
        self, count: int, rng: np.random.Generator, face_mask: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Area-weighted random surface points (count, 3) and their faces (count,), on ``face_mask`` faces."""
        return sample_surface_points(self.vertices, self.faces, count, rng, face_mask)


def load_grasp_object(path: Path, need_affordance: bool = False) -> GraspObject:
    """Read a PLY mesh to grasp.

    Raises:
        AffnerfError: naming the file, when it is missing, empty, non-finite, or lacks the ``affordance``
            property while ``need_affordance``.
    """
    mesh = read_labelled_ply(Path(path))
    obj = GraspObject.from_mesh(mesh, str(path))
    if need_affordance and obj.face_affordance is None:
        raise input_error(path, "mesh has no 'affordance' property (needed to restrict grasps to an affordance)")
    if np.ptp(obj.vertices, axis=0).max() <= 0:
        raise input_error(path, "mesh has no extent")
    return obj
