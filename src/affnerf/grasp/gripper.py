"""The parallel-jaw gripper and the grasp frame.

A grasp is a 4x4 pose of the gripper in the object's frame and an opening width. In the grasp frame the origin
is the point midway between the finger pads, +x is the closing axis (finger 1 sits at -x, finger 2 at +x), +z is
the approach direction (the gripper moves along +z to reach the object; the palm lies on the -z side), and
+y = z x x. conventions §6: opening at most 0.08 m, finger pads 0.02 m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh


@dataclass(frozen=True)
class ParallelJawGripper:
    """Dimensions in metres.

    Attributes:
        max_opening: widest distance between the pads.
        pad_size: side of each square finger pad (along y and z).
        finger_thickness: finger thickness along the closing axis.
        finger_length: length of each finger from the pad's far edge back to the palm (along z).
        palm_depth: palm thickness along z.
        palm_height: palm size along y.
    """

    max_opening: float = 0.08
    pad_size: float = 0.02
    finger_thickness: float = 0.008
    finger_length: float = 0.05
    palm_depth: float = 0.02
    palm_height: float = 0.03

    def boxes(self, width: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """The gripper's solids at an opening ``width``: (centre (3,), half extents (3,)) boxes in the grasp frame,
        finger 1, finger 2, palm. The pads' inner faces are at x = -width/2 and +width/2; the fingertips reach
        half a pad beyond the grasp centre along +z."""
        t, p, length = self.finger_thickness, self.pad_size, self.finger_length
        tip = p / 2.0
        z_mid = tip - length / 2.0
        half_finger = np.array([t / 2.0, p / 2.0, length / 2.0])
        finger1 = (np.array([-width / 2.0 - t / 2.0, 0.0, z_mid]), half_finger)
        finger2 = (np.array([width / 2.0 + t / 2.0, 0.0, z_mid]), half_finger)
        palm_x = width / 2.0 + t
        palm = (
            np.array([0.0, 0.0, tip - length - self.palm_depth / 2.0]),
            np.array([palm_x, self.palm_height / 2.0, self.palm_depth / 2.0]),
        )
        return [finger1, finger2, palm]

    def reach(self, width: float) -> float:
        """How far the solids at an opening ``width`` reach from the grasp centre: the distance to their farthest
        corner, metres (nothing farther can touch them)."""
        return max(float(np.linalg.norm(np.abs(centre) + half)) for centre, half in self.boxes(width))

    def meshes(self, width: float) -> list[trimesh.Trimesh]:
        """Box meshes of the fingers and palm at ``width``, in the grasp frame."""
        out = []
        for centre, half in self.boxes(width):
            box = trimesh.creation.box(extents=2.0 * half)
            box.apply_translation(centre)
            out.append(box)
        return out


def grasp_pose(centre: np.ndarray, axis: np.ndarray, approach: np.ndarray) -> np.ndarray:
    """(4, 4) grasp pose from its centre, closing axis and approach direction (made orthogonal to the axis).

    Example:
        >>> grasp_pose(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]))[:3, :3].tolist()
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """
    x = axis / np.linalg.norm(axis)
    z = approach - (approach @ x) * x
    z /= np.linalg.norm(z)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, centre
    return pose
