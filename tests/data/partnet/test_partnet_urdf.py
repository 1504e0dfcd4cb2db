"""URDF parsing: links, visuals, joints, lenient numbers, and errors naming the file."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from affnerf.data.partnet.fixture import DRAWER_LIMITS, HINGE
from affnerf.data.partnet.urdf import origin_matrix, parse_number, parse_urdf, rpy_matrix
from affnerf.errors import AffnerfError


def test_fixture_urdf_links_and_joints(toy_cabinet: Path) -> None:
    urdf = parse_urdf(toy_cabinet / "mobility.urdf")
    assert list(urdf.links) == ["base", "link_0", "link_1", "link_2"]
    assert [v.filename for v in urdf.links["link_0"].visuals] == [
        "textured_objs/original-3.obj",
        "textured_objs/original-4.obj",
    ]
    assert np.allclose(urdf.links["link_0"].visuals[0].origin[:3, 3], -np.asarray(HINGE))
    joints = {j.name: j for j in urdf.joints}
    assert {n: j.type for n, j in joints.items()} == {"joint_0": "revolute", "joint_1": "prismatic", "joint_2": "fixed"}
    assert (joints["joint_1"].parent, joints["joint_1"].child) == ("link_2", "link_1")
    assert np.allclose(joints["joint_1"].axis, [0, 0, 1])
    assert (joints["joint_1"].lower, joints["joint_1"].upper) == DRAWER_LIMITS
    assert np.allclose(joints["joint_0"].origin[:3, 3], HINGE)


def test_base_rpy_turns_mesh_y_up_into_z_up(toy_cabinet: Path) -> None:
    base = {j.name: j for j in parse_urdf(toy_cabinet / "mobility.urdf").joints}["joint_2"]
    rot = base.origin[:3, :3]
    assert np.allclose(rot @ [0, 1, 0], [0, 0, 1])  # up
    assert np.allclose(rot @ [0, 0, 1], [-1, 0, 0])  # the front (mesh +z) faces world -x


def test_rpy_is_fixed_axes_xyz() -> None:
    r, p, y = 0.3, -0.7, 1.1
    rx = origin_matrix(np.zeros(3), np.array([r, 0, 0]))[:3, :3]
    ry = rpy_matrix(np.array([0, p, 0]))
    rz = rpy_matrix(np.array([0, 0, y]))
    assert np.allclose(rpy_matrix(np.array([r, p, y])), rz @ ry @ rx)


def test_malformed_limit_is_salvaged_with_a_warning(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    from affnerf.data.partnet import write_partnet_fixture

    src = write_partnet_fixture(tmp_path / "obj", malformed_limit=True)
    with caplog.at_level(logging.WARNING):
        urdf = parse_urdf(src / "mobility.urdf")
    drawer = {j.name: j for j in urdf.joints}["joint_1"]
    assert drawer.lower == pytest.approx(-0.008)
    text = caplog.text
    assert "mobility.urdf" in text and "limit lower" in text and "-z0.008" in text


@pytest.mark.parametrize(
    ("token", "value"), [("0.5", 0.5), ("-z0.008", -0.008), ("1e-3", 1e-3), ("0.3z", 0.3), ("--0.2", -0.2)]
)
def test_parse_number(token: str, value: float) -> None:
    assert parse_number(token, Path("m.urdf"), "x") == pytest.approx(value)


@pytest.mark.parametrize("token", ["abc", "", "1.0.2.3", "nan", "inf"])
def test_unsalvageable_numbers_name_the_file(token: str) -> None:
    with pytest.raises(AffnerfError, match="m.urdf"):
        parse_number(token, Path("m.urdf"), "joint 'j' limit upper")


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


@pytest.mark.parametrize(
    ("old", "new", "problem"),
    [
        ("</robot>", "", "not a valid XML"),
        ('upper="0.3"', 'upper="zz"', "cannot read a number"),
        ('type="prismatic"', 'type="planar"', "unsupported joint type"),
        ('<parent link="base"/>', '<parent link="nowhere"/>', "unknown link"),
        ('<axis xyz="0 0 1"/>', '<axis xyz="0 0"/>', "expected 3 numbers"),
    ],
)
def test_broken_urdf_names_the_file(toy_cabinet: Path, old: str, new: str, problem: str) -> None:
    path = toy_cabinet / "mobility.urdf"
    _edit(path, old, new)
    with pytest.raises(AffnerfError, match=problem) as info:
        parse_urdf(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_missing_urdf(tmp_path: Path) -> None:
    with pytest.raises(AffnerfError, match="mobility.urdf: file not found"):
        parse_urdf(tmp_path / "mobility.urdf")
