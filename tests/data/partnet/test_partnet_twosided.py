"""Faces modelled twice in opposite windings (as in real PartNet-Mobility files): one kept, views shade correctly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from affnerf.data.cameras import Intrinsics
from affnerf.data.partnet import load_partnet_object, write_partnet_fixture
from affnerf.data.partnet.objfile import read_obj
from affnerf.data.partnet.twosided import drop_back_copies, face_normals, opposite_pairs
from affnerf.data.raycast import FrameCaster
from affnerf.objects.asset import ObjectAsset, merge_parts
from affnerf.predict.predictor import turntable_poses


def _views(asset: ObjectAsset) -> list[np.ndarray]:
    """(H, W, 3) uint8 views of the asset from four sides and from above."""
    caster = FrameCaster(merge_parts(asset))
    intr = Intrinsics.from_fov(96, 72, 0.9)
    poses = [*turntable_poses(4, 20.0, 1.0), *turntable_poses(1, 70.0, 1.0)]
    return [caster.cast_frame(intr, pose).rgb for pose in poses]


def _whitish(rgb: np.ndarray) -> float:
    """Share of non-background pixels whose channels are all >= 245 (the white back faces)."""
    obj = np.any(rgb != 255, axis=-1)
    return float((rgb[obj].min(axis=-1) >= 245).mean())


def test_pairs_are_faces_on_the_same_positions_in_opposite_winding() -> None:
    v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]])  # vertex 4 repeats vertex 1's position
    faces = np.array([[0, 1, 2], [2, 1, 0], [0, 2, 3], [1, 2, 0], [3, 2, 0], [0, 4, 2], [0, 1, 1]])
    # 0 and 1 pair; 3 is 0 again (same winding, rotated); 2 and 4 pair; 5 repeats 0 through vertex 4; 6 is degenerate
    assert opposite_pairs(v, faces).tolist() == [[0, 1], [2, 4]]


def test_the_doubled_fixture_loads_as_the_plain_one(tmp_path: Path) -> None:
    plain = load_partnet_object(write_partnet_fixture(tmp_path / "plain"))
    doubled_src = write_partnet_fixture(tmp_path / "doubled", doubled_faces=True)
    door = read_obj(doubled_src / "textured_objs" / "original-3.obj")
    assert len(door.faces) == 24 and len(opposite_pairs(door.vertices, door.faces)) == 12  # every face twice
    doubled = load_partnet_object(doubled_src)
    for a, b in zip(plain.parts, doubled.parts, strict=True):
        assert a.name == b.name
        assert np.allclose(a.mesh.vertices, b.mesh.vertices) and np.array_equal(a.mesh.faces, b.mesh.faces)
        assert [m.color for m in a.materials] == [m.color for m in b.materials]
        assert np.array_equal(a.face_material, b.face_material)
        assert (a.face_uv is None and b.face_uv is None) or np.array_equal(a.face_uv, b.face_uv)


def test_doubled_faces_render_like_the_plain_mesh(tmp_path: Path) -> None:
    plain = _views(load_partnet_object(write_partnet_fixture(tmp_path / "plain")))
    doubled = _views(load_partnet_object(write_partnet_fixture(tmp_path / "doubled", doubled_faces=True)))
    for a, b in zip(plain, doubled, strict=True):
        assert _whitish(b) <= _whitish(a) + 0.01  # no white back-face panels
        assert np.abs(a.astype(int) - b.astype(int)).max() <= 1


def _open_box_obj(path: Path, backs_first: bool) -> Path:
    """A cube without its top (10 triangles), every face also in the opposite winding: the walls' inner copies
    textured (the outer ones plain), the bottom's inner copy plain like its outer one."""
    corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4)]  # outward: -x, +x, -y, +y, -z
    out = [f"f {q[0] + 1} {q[1] + 1} {q[2] + 1}\nf {q[0] + 1} {q[2] + 1} {q[3] + 1}" for q in quads]
    back = [f"f {q[2] + 1}/1 {q[1] + 1}/1 {q[0] + 1}/1\nf {q[3] + 1}/1 {q[2] + 1}/1 {q[0] + 1}/1" for q in quads]
    backs = ["usemtl wood", *back[:4], "usemtl plain", back[4]]
    faces = [*backs, "usemtl plain", *out] if backs_first else ["usemtl plain", *out, *backs]
    (path.parent / "box.mtl").write_text("newmtl plain\nKd 0.5 0.5 0.5\nnewmtl wood\nKd 1 1 1\nmap_Kd wood.png\n")
    Image.new("RGB", (2, 2), (150, 100, 50)).save(path.parent / "wood.png")
    lines = ["mtllib box.mtl", *(f"v {x} {y} {z}" for x, y, z in corners), "vt 0.5 0.5", *faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_an_open_box_keeps_its_outward_faces_whichever_copy_comes_first(tmp_path: Path) -> None:
    for backs_first in (True, False):
        mesh = drop_back_copies(read_obj(_open_box_obj(tmp_path / f"box{backs_first}.obj", backs_first)))
        assert len(mesh.faces) == 10
        tri = mesh.vertices[mesh.faces]
        outward = np.einsum("fc,fc->f", face_normals(mesh.vertices, mesh.faces), tri.mean(axis=1) - 0.5)
        # the walls by parity (their textured inner copies lose), the bottom (open above) by the centre rule
        assert (outward > 0).all()
        assert [m.texture is None for m in mesh.materials] == [True]


def test_an_open_sheet_keeps_its_textured_side(tmp_path: Path) -> None:
    (tmp_path / "s.mtl").write_text("newmtl white\nKd 1 1 1\nnewmtl wood\nKd 1 1 1\nmap_Kd wood.png\n")
    Image.new("RGB", (2, 2), (150, 100, 50)).save(tmp_path / "wood.png")
    quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    (tmp_path / "s.obj").write_text(
        f"mtllib s.mtl\n{quad}usemtl white\nf 1 2 3\nf 1 3 4\nusemtl wood\nf 3/3 2/2 1/1\nf 4/4 3/3 1/1\n"
    )
    mesh = drop_back_copies(read_obj(tmp_path / "s.obj"))
    assert mesh.faces.tolist() == [[2, 1, 0], [3, 2, 0]] and mesh.materials[0].texture is not None
    assert mesh.face_uv is not None and mesh.face_uv[0].tolist() == [[1, 1], [1, 0], [0, 0]]


def test_shared_cabinet_views_have_no_white_back_faces(shared_partnet: Path) -> None:
    for view in _views(load_partnet_object(shared_partnet / "40147")):
        assert _whitish(view) < 0.02  # about 30 % of the cabinet was white back faces before
