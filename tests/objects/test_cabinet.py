"""Cabinet articulation: doors turn about their hinges, drawers slide out along -y, the carcass stays put."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from affnerf.errors import AffnerfError
from affnerf.objects.asset import Material
from affnerf.objects.categories import cabinet

MATS = (Material((0.6, 0.4, 0.2)), Material((0.7, 0.5, 0.3)), Material((0.7, 0.7, 0.7)))


def _params(seed: int = 3, **changes) -> cabinet.CabinetParams:
    """A cabinet with two doors and two drawers (other fields from ``seed``), closed unless ``changes`` say."""
    p = cabinet.sample_params(np.random.default_rng(seed))
    base = dict(n_doors=2, n_drawers=2, n_shelves=1, door_angles=(0.0, 0.0), drawer_openings=(0.0, 0.0))
    return replace(p, **{**base, **changes})


def _parts(asset):
    return {part.name: part.mesh for part in asset.parts}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_opening_a_door_turns_it_about_its_hinge_and_leaves_the_rest(seed):
    p = _params(seed)
    angle = 0.7
    closed = _parts(cabinet.build(p, *MATS))
    opened_asset = cabinet.build(p, *MATS, joints={"door_left": angle})
    opened = _parts(opened_asset)
    door0, door1 = closed["door_left"].vertices, opened["door_left"].vertices
    hinge = np.array([door0[:, 0].min(), door0[:, 1].max()])  # outer edge of the door's back face
    far = np.argmax(door0[:, 0])
    before, after = door0[far, :2] - hinge, door1[far, :2] - hinge
    turned = np.arctan2(after[1], after[0]) - np.arctan2(before[1], before[0])
    assert turned == pytest.approx(-angle)  # clockwise seen from above: the free edge swings out towards -y
    assert np.linalg.norm(after) == pytest.approx(np.linalg.norm(before))
    assert door1[far, 1] < door0[far, 1]
    np.testing.assert_allclose(door1[:, 2], door0[:, 2])
    # the handle turns with the door; frame, shelves, other door and drawers do not move
    assert not np.allclose(opened["handle_door_left"].vertices, closed["handle_door_left"].vertices)
    for name in ("frame", "base", "shelf_0", "door_right", "drawer_0_front", "drawer_1_box"):
        np.testing.assert_array_equal(opened[name].vertices, closed[name].vertices)
    joint = {j.name: j for j in opened_asset.joints}["door_left"]
    assert joint.type == "revolute" and joint.value == angle and joint.parts == ("door_left", "handle_door_left")


def test_opening_a_drawer_slides_front_box_and_handle_out_along_minus_y():
    p = _params()
    d = 0.123
    closed = _parts(cabinet.build(p, *MATS))
    opened = _parts(cabinet.build(p, *MATS, joints={"drawer_1": d}))
    for name in ("drawer_1_front", "drawer_1_box", "handle_drawer_1"):
        shift = opened[name].vertices - closed[name].vertices
        np.testing.assert_allclose(shift, np.broadcast_to([0.0, -d, 0.0], shift.shape), atol=1e-12)
    np.testing.assert_array_equal(opened["drawer_0_front"].vertices, closed["drawer_0_front"].vertices)
    np.testing.assert_array_equal(opened["frame"].vertices, closed["frame"].vertices)


def test_carcass_is_hollow_behind_the_doors():
    p = _params(n_shelves=0)
    parts = _parts(cabinet.build(p, *MATS))
    edges = cabinet.band_edges(p)
    inside = np.array([[0.0, 0.0, 0.5 * (edges[0] + edges[1])]])  # middle of the door compartment
    assert not parts["frame"].contains(inside)[0]
    assert parts["frame"].bounds[0, 2] == pytest.approx(p.base_height)


def test_unknown_or_out_of_range_joint_states_are_refused():
    p = _params()
    with pytest.raises(AffnerfError):
        cabinet.build(p, *MATS, joints={"door": 0.3})  # a two-door cabinet has door_left and door_right
    with pytest.raises(AffnerfError):
        cabinet.build(p, *MATS, joints={"drawer_0": p.depth})  # beyond 0.8 x depth
