"""Objects to grasp: a labelled mesh with what planning and scoring need (normals, labels, ray casting), and
the contacts a parallel-jaw gripper makes when it closes on it."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from affnerf.data.render import RayCaster
from affnerf.errors import input_error
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.quality import object_radius
from affnerf.meshio import LabelledMesh, read_labelled_ply
from affnerf.predict.mesh import face_labels
from affnerf.vocab import AFFORDANCE_CLASSES


@dataclass
class GraspObject:
    """A mesh to grasp, in metres.

    Attributes:
        vertices: (V, 3).
        faces: (F, 3).
        face_affordance: (F,) affordance ids, or None when the mesh carries no labels.
        name: where it came from (for messages).
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_affordance: np.ndarray | None = None
    name: str = "mesh"
    _caster: RayCaster | None = field(default=None, repr=False)

    @classmethod
    def from_mesh(cls, mesh: LabelledMesh, name: str = "mesh") -> GraspObject:
        """From a labelled mesh: per-face ``affordance`` if present, else the majority of its vertices'."""
        labels = mesh.face_props.get("affordance")
        if labels is None and "affordance" in mesh.vertex_props:
            labels = face_labels(mesh.faces, np.asarray(mesh.vertex_props["affordance"]))
        return cls(np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64),
                   None if labels is None else np.asarray(labels, np.int64), name)  # fmt: skip

    @property
    def caster(self) -> RayCaster:
        if self._caster is None:
            self._caster = RayCaster(self.vertices, self.faces)
        return self._caster

    @cached_property
    def face_areas(self) -> np.ndarray:
        tri = self.vertices[self.faces]
        return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)

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
        return [AFFORDANCE_CLASSES[int(c)] if 0 <= c < len(AFFORDANCE_CLASSES) else str(int(c)) for c in self.face_affordance[faces]]

    def sample_surface(
        self, count: int, rng: np.random.Generator, face_mask: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Area-weighted random surface points (count, 3) and their faces (count,), on ``face_mask`` faces."""
        weights = self.face_areas if face_mask is None else self.face_areas * face_mask
        total = weights.sum()
        if total <= 0:
            return np.zeros((0, 3)), np.zeros(0, np.int64)
        faces = rng.choice(len(self.faces), count, p=weights / total)
        r = rng.random((count, 2))
        flip = r.sum(1) > 1
        r[flip] = 1 - r[flip]
        tri = self.vertices[self.faces[faces]]
        points = tri[:, 0] + r[:, :1] * (tri[:, 1] - tri[:, 0]) + r[:, 1:] * (tri[:, 2] - tri[:, 0])
        return points, faces


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


@dataclass
class Contacts:
    """Where closing jaws touch the object, for G grasps.

    Attributes:
        points: (G, 2, 3) contact of finger 1 (at -x) and finger 2 (at +x).
        faces: (G, 2) their faces (-1 where none).
        width: (G,) distance between the contacts along the closing axis.
        valid: (G,) both fingers touch an outside surface within the opening.
    """

    points: np.ndarray
    faces: np.ndarray
    width: np.ndarray
    valid: np.ndarray


def pad_offsets(gripper: ParallelJawGripper, per_side: int = 3) -> np.ndarray:
    """(per_side^2, 2) (y, z) offsets of probe rays over a finger pad, in the grasp frame."""
    s = np.linspace(-0.4, 0.4, per_side) * gripper.pad_size
    yy, zz = np.meshgrid(s, s)
    return np.stack([yy.ravel(), zz.ravel()], 1)


def close_jaws(
    obj: GraspObject, poses: np.ndarray, gripper: ParallelJawGripper = ParallelJawGripper(), patch_tolerance: float = 0.001
) -> Contacts:
    """Close the jaws of grasps (G, 4, 4) from full opening until each pad first touches the object.

    Each pad probes with a few rays spread over its face along the closing axis. The pad stops at the first
    touch; its contact is the centre of the patch of probes that touch within ``patch_tolerance`` of it (a flat
    pad on a flat side touches a patch, not a point). A pad starting inside the object (the object wider than the
    opening there) or touching nothing makes the grasp invalid.
    """
    g = len(poses)
    offsets = pad_offsets(gripper)
    k = len(offsets)
    half = gripper.max_opening / 2.0
    x, y, z, c = poses[:, :3, 0], poses[:, :3, 1], poses[:, :3, 2], poses[:, :3, 3]
    lateral = offsets[None, :, 0:1] * y[:, None, :] + offsets[None, :, 1:2] * z[:, None, :]  # (G, K, 3)
    points = np.zeros((g, 2, 3))
    faces = np.full((g, 2), -1)
    depth = np.full((g, 2), np.inf)
    for finger, sign in ((0, -1.0), (1, 1.0)):
        starts = c[:, None, :] + sign * half * x[:, None, :] + lateral  # (G, K, 3)
        dirs = np.broadcast_to(-sign * x[:, None, :], (g, k, 3))
        ray, face, t, _ = obj.caster.cast(starts.reshape(-1, 3), dirs.reshape(-1, 3))
        t_all = np.full(g * k, np.inf)
        face_all = np.full(g * k, -1)
        t_all[ray], face_all[ray] = t, face
        t_all, face_all = t_all.reshape(g, k), face_all.reshape(g, k)
        first = t_all.min(axis=1)
        depth[:, finger] = first
        # a flat pad touches a patch: the probes within a millimetre of the first touch
        patch = np.isfinite(t_all) & (t_all <= first[:, None] + patch_tolerance)
        hits = starts + np.where(np.isfinite(t_all), t_all, 0.0)[..., None] * dirs
        count = np.maximum(patch.sum(axis=1), 1)
        points[:, finger] = (hits * patch[..., None]).sum(axis=1) / count[:, None]
        # the patch's face nearest its centre gives the contact's normal and label
        gap = np.where(patch, np.linalg.norm(hits - points[:, finger, None, :], axis=-1), np.inf)
        faces[:, finger] = face_all[np.arange(g), gap.argmin(axis=1)]
    width = gripper.max_opening - depth.sum(axis=1)
    valid = np.isfinite(depth).all(axis=1) & (width > 0)
    for finger, sign in ((0, -1.0), (1, 1.0)):
        ok = faces[:, finger] >= 0
        entering = np.zeros(g, bool)
        entering[ok] = (obj.face_normals[faces[ok, finger]] * (-sign * x[ok])).sum(1) < 0  # front face hit
        valid &= entering
    return Contacts(points, faces, np.where(valid, width, 0.0), valid)
