"""Scoring given grasps on a mesh: close the jaws on it, then epsilon and the affordance at each contact."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from affnerf.grasp.contacts import close_jaws, score_contacts
from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.quality import MU
from affnerf.grasp.target import GraspObject


@dataclass
class GraspScore:
    """A grasp as scored on a mesh.

    Attributes:
        epsilon: Ferrari-Canny quality of the contacts the jaws make on this mesh (0 if they make none).
        width: opening at contact.
        contacts: (2, 3) contact points (zeros when invalid).
        affordance: affordance names at the two contacts (``none`` where a finger touches nothing).
        valid: both fingers touch the outside of the mesh within the opening.
    """

    epsilon: float
    width: float
    contacts: np.ndarray
    affordance: list[str]
    valid: bool

    def on(self, affordance: str) -> bool:
        """Whether both contacts lie on ``affordance``."""
        return self.valid and all(a == affordance for a in self.affordance)

    def to_json(self) -> dict:
        return {
            "epsilon": self.epsilon,
            "width": round(self.width, 6),
            "contacts": np.round(self.contacts, 6).tolist(),
            "affordance": self.affordance,
            "valid": self.valid,
        }


def score_grasps(
    obj: GraspObject, poses: np.ndarray, gripper: ParallelJawGripper = ParallelJawGripper(), mu: float = MU
) -> list[GraspScore]:
    """Score grasps (G, 4, 4) on ``obj`` (typically ground truth, whatever mesh they were planned on)."""
    if not len(poses):
        return []
    contacts = close_jaws(obj, np.asarray(poses), gripper)
    eps = score_contacts(obj, contacts, np.asarray(poses), mu)
    out = []
    for g in range(len(poses)):
        valid = bool(contacts.valid[g])
        names = obj.label_names(contacts.faces[g]) if valid else ["none", "none"]
        out.append(GraspScore(float(eps[g]), float(contacts.width[g]), contacts.points[g], names, valid))
    return out
