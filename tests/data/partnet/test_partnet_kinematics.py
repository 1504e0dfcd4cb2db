"""Forward kinematics: joint motions with hand-computed values, state modes, and the toy cabinet's links."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from affnerf.data.partnet.fixture import HINGE
from affnerf.data.partnet.kinematics import descendant_links, joint_values, link_poses
from affnerf.data.partnet.urdf import Joint, Link, Urdf, origin_matrix, parse_urdf
from affnerf.errors import AffnerfError


def _joint(name: str, jtype: str, xyz=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0), limits=(0.0, 0.0), parent="a", child="b"):
    origin = origin_matrix(np.asarray(xyz, float), np.zeros(3))
    return Joint(name, jtype, parent, child, origin, np.asarray(axis, float), *limits, True)  # type: ignore[arg-type]


def _urdf(*joints: Joint) -> Urdf:
    names = {n for j in joints for n in (j.parent, j.child)}
    return Urdf(Path("m.urdf"), "t", {n: Link(n) for n in sorted(names)}, tuple(joints))


def test_revolute_rotates_about_the_axis_through_the_joint_origin() -> None:
    urdf = _urdf(_joint("j", "revolute", xyz=(1, 0, 0), limits=(-np.pi, np.pi)))
    pose = link_poses(urdf, {"j": np.pi / 2})["b"]
    assert np.allclose(pose @ [1, 0, 0, 1], [1, 1, 0, 1])  # child point (1,0,0): rotated to (0,1,0), then moved
    assert np.allclose(pose @ [0, 0, 0, 1], [1, 0, 0, 1])  # the joint origin stays


def test_prismatic_slides_along_the_axis_in_the_joint_frame() -> None:
    j = _joint("j", "prismatic", xyz=(0, 0, 1), axis=(0, 1, 0), limits=(0, 1))
    pose = link_poses(_urdf(j), {"j": 0.25})["b"]
    assert np.allclose(pose[:3, 3], [0, 0.25, 1])


def test_chain_composes_parent_origin_motion() -> None:
    j1 = _joint("j1", "revolute", xyz=(0, 0, 1), limits=(-4, 4), parent="a", child="b")
    j2 = _joint("j2", "prismatic", xyz=(1, 0, 0), axis=(1, 0, 0), limits=(0, 1), parent="b", child="c")
    pose = link_poses(_urdf(j1, j2), {"j1": np.pi / 2, "j2": 0.5})["c"]
    assert np.allclose(pose[:3, 3], [0, 1.5, 1])  # (1 + 0.5) along x, turned onto +y, lifted by 1


@pytest.mark.parametrize(("limits", "rest"), [((-0.108, -0.008), -0.008), ((0.1, 0.5), 0.1), ((-1, 1), 0.0)])
def test_rest_is_zero_clamped_into_the_limits(limits: tuple[float, float], rest: float) -> None:
    assert joint_values(_urdf(_joint("j", "prismatic", limits=limits)), "rest") == {"j": pytest.approx(rest)}


def test_random_values_lie_within_the_limits_and_repeat_with_the_seed() -> None:
    urdf = _urdf(
        _joint("door", "revolute", limits=(0.0, 1.5), child="b"),
        _joint("spin", "continuous", child="c"),
        _joint("fix", "fixed", child="d"),
    )
    draws = [joint_values(urdf, "random", np.random.default_rng(s)) for s in range(50)]
    assert all(set(d) == {"door", "spin"} for d in draws)
    assert all(0.0 <= d["door"] <= 1.5 and 0.0 <= d["spin"] < 2 * np.pi for d in draws)
    assert max(d["spin"] for d in draws) > np.pi  # continuous joints use the whole turn
    same = [joint_values(urdf, "random", np.random.default_rng(7)) for _ in range(2)]
    assert same[0] == same[1]


def test_modes_are_checked() -> None:
    urdf = _urdf(_joint("j", "revolute", limits=(0, 1)))
    with pytest.raises(AffnerfError, match="unknown joint state mode"):
        joint_values(urdf, "open")
    with pytest.raises(ValueError, match="rng"):
        joint_values(urdf, "random")


def test_cycle_is_an_error() -> None:
    urdf = _urdf(_joint("j1", "fixed", parent="a", child="b"), _joint("j2", "fixed", parent="b", child="a"))
    with pytest.raises(AffnerfError, match="cycle"):
        link_poses(urdf, {})


def test_toy_cabinet_door_and_drawer_move_outwards(toy_cabinet: Path) -> None:
    urdf = parse_urdf(toy_cabinet / "mobility.urdf")
    closed = link_poses(urdf, {"joint_0": 0.0, "joint_1": 0.0})
    opened = link_poses(urdf, {"joint_0": np.pi / 2, "joint_1": 0.3})
    # drawer: slides 0.3 along the mesh's +z, which the base joint turns onto world -x (the front)
    assert np.allclose(opened["link_1"][:3, 3] - closed["link_1"][:3, 3], [-0.3, 0, 0])
    # door: the hinge stays put, the far edge (0.6 m left of the hinge in the mesh) swings out to the front
    door_visual = urdf.links["link_0"].visuals[0].origin
    hinge, far = np.array([*HINGE, 1.0]), np.array([HINGE[0] - 0.6, HINGE[1], HINGE[2], 1.0])
    for pose in (closed, opened):
        assert np.allclose(pose["link_0"] @ door_visual @ hinge, closed["link_0"] @ door_visual @ hinge)
    moved = (opened["link_0"] @ door_visual @ far - closed["link_0"] @ door_visual @ far)[:3]
    assert moved[0] < -0.5  # towards the front (world -x)


def test_descendant_links(toy_cabinet: Path) -> None:
    urdf = parse_urdf(toy_cabinet / "mobility.urdf")
    assert descendant_links(urdf, "link_2") == {"link_0", "link_1", "link_2"}
    assert descendant_links(urdf, "link_0") == {"link_0"}
