"""A closed surface through a stack of cross-section rings (a loft), for bodies whose section changes shape.

:func:`affnerf.objects.primitives.sweep` keeps one cross-section along its path; a bottle whose square body
rounds off into a circular neck, or a lobed (melon) teapot, needs the section itself to change from ring to ring.
"""

from __future__ import annotations

import numpy as np
import trimesh


def _quads(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Two triangles per edge between index rings ``a`` and ``b`` (each (M,)) -> (2M, 3)."""
    a2, b2 = np.roll(a, -1), np.roll(b, -1)
    return np.concatenate([np.stack([a, a2, b2], 1), np.stack([a, b2, b], 1)])


def loft(rings: np.ndarray) -> trimesh.Trimesh:
    """Join rings of points into a closed surface, capping both ends with a fan to the end ring's centroid.

    Args:
        rings: (N, M, 3) N >= 2 rings of M points each; point j of every ring corresponds to point j of the
            next, and every ring is star-shaped about its centroid (as the sections of a body are).

    Returns:
        A watertight, consistently wound mesh with outward normals.

    Example:
        >>> t = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        >>> ring = np.stack([np.cos(t), np.sin(t), np.zeros(16)], 1)
        >>> loft(np.stack([ring, ring + [0, 0, 1]])).is_watertight
        True
    """
    rings = np.asarray(rings, np.float64)
    n, m, _ = rings.shape
    idx = np.arange(n * m).reshape(n, m)
    faces = [_quads(idx[i], idx[i + 1]) for i in range(n - 1)]
    bottom, top = n * m, n * m + 1
    faces.append(np.stack([np.full(m, bottom), np.roll(idx[0], -1), idx[0]], 1))
    faces.append(np.stack([np.full(m, top), idx[-1], np.roll(idx[-1], -1)], 1))
    vertices = np.concatenate([rings.reshape(-1, 3), rings[0].mean(0, keepdims=True), rings[-1].mean(0, keepdims=True)])
    mesh = trimesh.Trimesh(vertices=vertices, faces=np.concatenate(faces), process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh
