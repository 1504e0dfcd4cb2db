"""The 3D protocol's surface samples: only a mesh's outer surface is compared."""

from __future__ import annotations

import numpy as np
import trimesh

from affnerf.eval.surface import mesh_samples, score_mesh
from affnerf.meshio import LabelledMesh


def _capped_rod(rod_top: float = 0.1) -> LabelledMesh:
    """A rod along z (radius 1 cm, from -10 cm to ``rod_top``, label 1) and a cap (radius 1.3 cm, from 2.5 to 10.5 cm,
    label 5) over its top end."""
    rod = trimesh.creation.cylinder(radius=0.01, height=rod_top + 0.1, sections=48)
    rod.apply_translation((0.0, 0.0, (rod_top - 0.1) / 2))
    lid = trimesh.creation.cylinder(radius=0.013, height=0.08, sections=48)
    lid.apply_translation((0.0, 0.0, 0.065))
    both = trimesh.util.concatenate([rod, lid])
    labels = np.concatenate([np.full(len(rod.faces), 1), np.full(len(lid.faces), 5)])
    return LabelledMesh(np.asarray(both.vertices), np.asarray(both.faces), face_props={"affordance": labels})


def test_samples_leave_out_the_faces_under_another_part():
    samples = mesh_samples(_capped_rod(), [0, 1])
    radius = np.hypot(samples.points[:, 0], samples.points[:, 1])
    under_cap = (samples.points[:, 2] > 0.03) & (samples.points[:, 2] < 0.101) & (radius < 0.0125)
    assert len(samples) > 12000 and not under_cap.any()  # the rod's end inside the cap is gone
    assert set(np.unique(samples.labels).tolist()) == {1, 5}


def test_a_prediction_of_the_outer_surface_scores_as_the_truth_itself():
    # The rod stopping where the cap begins is the same object seen from outside, labelled the same: it must score
    # (almost) perfect 3D affordance mIoU. Counting the rod's hidden end, labelled 1 inside the cap whose nearest
    # predicted points are the cap's, would cost it the rod class's IoU there.
    truth = mesh_samples(_capped_rod(), [0, 2])
    score = score_mesh(_capped_rod(rod_top=0.025), truth, [0, 3])
    assert score["fscore_1cm"] > 0.99 and score["affordance_miou_3d"] > 0.97
