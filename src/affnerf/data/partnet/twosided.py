"""Faces modelled twice, once per side: keep the one that faces out.

Real PartNet-Mobility OBJs hold most faces twice: a second copy on the same three vertices in the opposite winding,
usually in a plain white material (the back of a textured face). A ray caster hits whichever copy of such a pair its
acceleration structure reaches first, so imported views showed half-white diagonal panels. The importer keeps one
face of each pair, the one facing out of the mesh, decided by the first of these rules that tells the copies apart:

1. parity: a ray leaving a face along its normal crosses the mesh's surface an even number of times on its way to
   infinity when the normal points out of a closed surface, an odd number when it points in (coincident copies
   count once); the copy with the even count is kept;
2. texture: on an open sheet (both counts even, or both odd) the textured copy, when only one is textured;
3. centre: the copy facing away from the mean of the mesh's vertices (the first in the file when neither does).

The ray caster shades both sides of a face alike (``|cos|``), so the kept face looks the same from either side.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from affnerf.data.partnet.objfile import ObjMesh

#: Barycentric weights of the point each ray starts from: inside the face, off its medians and edges.
RAY_START = np.array([0.47, 0.31, 0.22])
#: Ray offset and step past each hit, as a fraction of the mesh's largest extent.
RAY_STEP = 1e-5
#: Crossings counted per ray at most; a ray that reaches this count leaves its pair to the other rules.
MAX_CROSSINGS = 64


def position_ids(vertices: np.ndarray, decimals: int = 9) -> np.ndarray:
    """(V,) int64 ids of the vertices' positions: equal ids for vertices at the same place (rounded)."""
    _, ids = np.unique(np.round(vertices, decimals), axis=0, return_inverse=True)
    return ids.reshape(-1).astype(np.int64)


def canonical_cycles(corners: np.ndarray) -> np.ndarray:
    """(F, 3) each row rotated to start at its smallest entry, so equal cycles (same winding) have equal rows.

    Example:
        >>> canonical_cycles(np.array([[5, 2, 9], [2, 9, 5]])).tolist()
        [[2, 9, 5], [2, 9, 5]]
    """
    start = np.argmin(corners, axis=1)
    order = (start[:, None] + np.arange(3)) % 3
    return np.take_along_axis(corners, order, axis=1)


def opposite_pairs(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Faces on the same three positions in opposite winding.

    Args:
        vertices: (V, 3) positions.
        faces: (F, 3) vertex indices.

    Returns:
        (P, 2) int64 face indices ``(earlier, later)`` in file order; a face is in at most one pair (with the
        first face of the opposite cycle), degenerate faces in none.

    Example:
        >>> v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> opposite_pairs(v, np.array([[0, 1, 2], [0, 1, 2], [2, 1, 0]])).tolist()
        [[0, 2]]
    """
    n = len(faces)
    ids = position_ids(vertices)[faces]
    proper = (ids[:, 0] != ids[:, 1]) & (ids[:, 1] != ids[:, 2]) & (ids[:, 0] != ids[:, 2])
    cycles = np.concatenate([canonical_cycles(ids), canonical_cycles(ids[:, ::-1])])  # (2F, 3): as wound, reversed
    _, keys = np.unique(cycles, axis=0, return_inverse=True)
    forward, backward = keys.reshape(-1)[:n], keys.reshape(-1)[n:]
    first = np.full(keys.max() + 1, n)
    np.minimum.at(first, forward[proper], np.flatnonzero(proper))
    index = np.arange(n)
    twin = first[backward]
    chosen = proper & (first[forward] == index) & (twin < n) & (index < twin)
    return np.stack([index[chosen], twin[chosen]], axis=1).astype(np.int64)


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F, 3) unit normals by winding (counter-clockwise seen from the side they point to)."""
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    return cross / np.maximum(np.linalg.norm(cross, axis=1, keepdims=True), 1e-30)


def surface_crossings(vertices: np.ndarray, faces: np.ndarray, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(N,) times rays (N, 3) from ``origins`` along unit ``dirs`` cross the mesh's surface on their way out.

    Hits at one place (coincident faces, a shared edge) count once. A ray still hitting after ``MAX_CROSSINGS``
    gets -1.
    """
    from affnerf.data.raycast import RayCaster  # loaded late: Embree sizes its threads on import (affnerf.data.pool)

    caster = RayCaster(vertices, faces)
    step = RAY_STEP * max(float(np.ptp(vertices, axis=0).max()), 1e-9)
    count = np.zeros(len(origins), np.int64)
    points = origins + step * dirs
    active = np.arange(len(origins))
    for _ in range(MAX_CROSSINGS):
        if not len(active):
            return count
        ray, _, t, _ = caster.cast(points[active], dirs[active])
        active = active[ray]
        count[active] += 1
        points[active] += (t[:, None] + step) * dirs[active]
    count[active] = -1
    return count


def keep_earlier(mesh: ObjMesh, pairs: np.ndarray) -> np.ndarray:
    """(P,) bool: whether to keep the earlier face of each pair (else the later), by parity, texture, centre."""
    normals = face_normals(mesh.vertices, mesh.faces)
    starts = np.einsum("k,fkc->fc", RAY_START, mesh.vertices[mesh.faces])
    first, second = pairs[:, 0], pairs[:, 1]
    crossings = surface_crossings(mesh.vertices, mesh.faces, starts[pairs.reshape(-1)], normals[pairs.reshape(-1)])
    outward = ((crossings >= 0) & (crossings % 2 == 0)).reshape(-1, 2)  # (P, 2): leaves a closed surface
    out_first, out_second = outward[:, 0], outward[:, 1]
    textured = np.array([m.texture is not None for m in mesh.materials])[mesh.face_material]
    facing = np.einsum("pc,pc->p", normals[first], starts[first] - mesh.vertices.mean(axis=0))
    by_texture = np.where(textured[first] != textured[second], textured[first], facing >= 0)
    return np.where(out_first != out_second, out_first, by_texture)


def keep_faces(mesh: ObjMesh, keep: np.ndarray) -> ObjMesh:
    """The mesh with only the faces where ``keep`` (F,) is true; unused vertices and materials are dropped."""
    used, faces = np.unique(mesh.faces[keep].reshape(-1), return_inverse=True)
    materials, face_material = np.unique(mesh.face_material[keep], return_inverse=True)
    return replace(
        mesh,
        vertices=mesh.vertices[used],
        faces=faces.reshape(-1, 3).astype(np.int64),
        face_uv=None if mesh.face_uv is None else mesh.face_uv[keep],
        face_material=face_material.reshape(-1).astype(np.int32),
        materials=tuple(mesh.materials[m] for m in materials),
    )


def drop_back_copies(mesh: ObjMesh) -> ObjMesh:
    """The mesh with one face of each opposite-winding pair, the one facing out (see the module's rules).

    Faces keep their file order; a mesh without such pairs is returned as it is.
    """
    pairs = opposite_pairs(mesh.vertices, mesh.faces)
    if not len(pairs):
        return mesh
    earlier = keep_earlier(mesh, pairs)
    keep = np.ones(len(mesh.faces), bool)
    keep[np.where(earlier, pairs[:, 1], pairs[:, 0])] = False
    return keep_faces(mesh, keep)
