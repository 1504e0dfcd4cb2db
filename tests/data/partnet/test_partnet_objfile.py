"""OBJ + MTL reading: faces in file order, per-corner UVs, per-face materials, textures, and errors."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from affnerf.data.partnet.fixture import fixture_texture
from affnerf.data.partnet.objfile import DEFAULT_MATERIAL, read_obj
from affnerf.errors import AffnerfError


def test_multi_material_obj_keeps_faces_uvs_and_materials(toy_cabinet: Path) -> None:
    mesh = read_obj(toy_cabinet / "textured_objs" / "original-3.obj")  # the door: front textured, rest plain
    assert mesh.faces.shape == (12, 3) and mesh.vertices.shape == (24, 3)
    assert len(mesh.materials) == 2
    textured = mesh.face_material == 0
    assert textured.sum() == 2  # the two triangles of the front
    assert mesh.materials[0].texture is not None and mesh.materials[0].color == (1.0, 1.0, 1.0)
    assert np.array_equal(mesh.materials[0].texture, fixture_texture())
    assert mesh.materials[1].texture is None
    assert mesh.face_uv is not None and mesh.face_uv.shape == (12, 3, 2)
    assert np.allclose(mesh.face_uv[~textured], 0.0)
    # the front's UVs span the unit square with u along +x and v along +y
    tri = mesh.vertices[mesh.faces[textured]]  # (2, 3, 3)
    uv = mesh.face_uv[textured]
    lo, hi = tri.reshape(-1, 3).min(0), tri.reshape(-1, 3).max(0)
    assert np.allclose(uv[..., 0], (tri[..., 0] - lo[0]) / (hi[0] - lo[0]))
    assert np.allclose(uv[..., 1], (tri[..., 1] - lo[1]) / (hi[1] - lo[1]))


def test_textures_are_shared_through_the_cache(toy_cabinet: Path) -> None:
    cache: dict = {}
    a = read_obj(toy_cabinet / "textured_objs" / "original-3.obj", cache)
    b = read_obj(toy_cabinet / "textured_objs" / "original-3.obj", cache)
    assert a.materials[0].texture is b.materials[0].texture and len(cache) == 1


def test_polygons_negative_indices_and_unused_vertices(tmp_path: Path) -> None:
    path = tmp_path / "quad.obj"
    path.write_text(
        "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf -4/-4 -3/-3 -2/-2 -1/-1\n"
    )
    mesh = read_obj(path)
    assert mesh.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]  # the unused vertex is dropped
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert mesh.face_uv is not None and mesh.face_uv[1].tolist() == [[0, 0], [1, 1], [0, 1]]
    assert mesh.materials == (DEFAULT_MATERIAL,)


def test_missing_mtl_falls_back_with_a_warning(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    path = tmp_path / "tri.obj"
    path.write_text("mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl wood\nf 1 2 3\n")
    with caplog.at_level(logging.WARNING):
        mesh = read_obj(path)
    assert mesh.materials == (DEFAULT_MATERIAL,) and mesh.face_uv is None
    assert "gone.mtl" in caplog.text and "'wood'" in caplog.text


@pytest.mark.parametrize(
    ("body", "problem"),
    [
        ("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "non-finite"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "out of range"),
        ("v 0 0 0\nv 1 0 x\n", "unreadable 'v'"),
        ("v 0 0 0\n", "no faces"),
    ],
)
def test_broken_obj_names_the_file(tmp_path: Path, body: str, problem: str) -> None:
    path = tmp_path / "broken.obj"
    path.write_text(body)
    with pytest.raises(AffnerfError, match=problem) as info:
        read_obj(path)
    assert str(info.value).startswith(str(path))


def test_missing_obj(tmp_path: Path) -> None:
    with pytest.raises(AffnerfError, match="gone.obj: file not found"):
        read_obj(tmp_path / "gone.obj")
