"""Contacts of a parallel-jaw gripper closing on an object, and the Ferrari-Canny quality of those contacts."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.quality import MU, ferrari_canny, grasp_wrenches, hold_quality
from affnerf.grasp.target import GraspObject


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
    obj: GraspObject,
    poses: np.ndarray,
    gripper: ParallelJawGripper = ParallelJawGripper(),
    patch_tolerance: float = 0.001,
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


def score_contacts(obj: GraspObject, contacts: Contacts, poses: np.ndarray, mu: float = MU) -> np.ndarray:
    """(G,) Ferrari-Canny epsilon of closed-jaw contacts (0 where the jaws find no valid pair); the friction
    cones are linearised relative to each grasp's approach axis."""
    out = np.zeros(len(contacts.valid))
    for g in np.flatnonzero(contacts.valid):
        inward = -obj.face_normals[contacts.faces[g]]
        out[g] = ferrari_canny(contacts.points[g], inward, obj.centroid, obj.radius, mu, reference=poses[g, :3, 2])
    return out


#: The object frame's vertical: canonical +z is up (conventions §1), and the physics test lifts along it.
UP = np.array([0.0, 0.0, 1.0])


def hold_contacts(
    obj: GraspObject, contacts: Contacts, poses: np.ndarray, mu: float = MU, up: np.ndarray = UP
) -> np.ndarray:
    """(G,) :func:`~affnerf.grasp.quality.hold_quality` of closed-jaw contacts: the least weight, in units of the
    total normal force, they carry at the object's centroid while it turns about the closing axis (0 where the jaws
    find no valid pair)."""
    out = np.zeros(len(contacts.valid))
    for g in np.flatnonzero(contacts.valid):
        inward = -obj.face_normals[contacts.faces[g]]
        wrenches = grasp_wrenches(contacts.points[g], inward, obj.centroid, obj.radius, mu, reference=poses[g, :3, 2])
        out[g] = hold_quality(wrenches, up, poses[g, :3, 0])
    return out
