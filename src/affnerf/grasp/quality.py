"""The Ferrari-Canny epsilon quality on the L1 grasp wrench space (conventions §6), as small pure functions.

Each contact pushes into the object along its inward normal with unit normal force; friction (coefficient mu) is
a cone linearised by ``edges`` directions; a soft finger adds a torsional moment about the normal of at most
``torsion`` metres times the normal force. Torques are divided by the object's radius (largest vertex distance
from the centroid) so forces and torques are comparable. The L1 wrench space is the convex hull of every
contact's primitive wrenches; epsilon is the distance from the origin to its boundary, and 0 when the origin is
not strictly inside.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

#: Default friction coefficient (conventions §6).
MU = 0.5
#: Default number of friction cone edges (conventions §6).
CONE_EDGES = 8
#: Default torsional moment per unit normal force (metres): friction over a pad patch of about 5 mm.
TORSION = MU * 0.005


def tangent_basis(normal: np.ndarray, reference: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors orthogonal to ``normal`` (3,) and to each other; the first along ``reference``
    projected on the tangent plane when given (so the linearised cone turns with the grasp, and the quality does
    not depend on the world frame)."""
    n = normal / np.linalg.norm(normal)
    u = None
    if reference is not None:
        u = reference - (reference @ n) * n
        u = u / np.linalg.norm(u) if np.linalg.norm(u) > 1e-9 else None
    if u is None:
        helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        u = np.cross(n, helper)
        u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def friction_cone(
    inward: np.ndarray, mu: float = MU, edges: int = CONE_EDGES, reference: np.ndarray | None = None
) -> np.ndarray:
    """(edges, 3) contact forces of unit normal component on the edges of the linearised friction cone.

    Example:
        >>> f = friction_cone(np.array([0.0, 0.0, 1.0]), mu=0.5, edges=4)
        >>> np.allclose(f[:, 2], 1.0), np.allclose(np.linalg.norm(f[:, :2], axis=1), 0.5)
        (True, True)
    """
    n = inward / np.linalg.norm(inward)
    u, v = tangent_basis(n, reference)
    angles = 2.0 * np.pi * np.arange(edges) / edges
    return n[None, :] + mu * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)


def contact_wrenches(
    point: np.ndarray,
    inward: np.ndarray,
    centroid: np.ndarray,
    radius: float,
    mu: float = MU,
    edges: int = CONE_EDGES,
    torsion: float = TORSION,
    reference: np.ndarray | None = None,
) -> np.ndarray:
    """(edges + 2, 6) primitive wrenches (force, torque / radius) a soft-finger contact can apply.

    Args:
        point: (3,) contact position.
        inward: (3,) normal pointing into the object (the finger pushes along it).
        centroid: (3,) the object's centroid (torque reference).
        radius: the object's radius (torque scale).
        mu: friction coefficient.
        edges: friction cone edges.
        torsion: largest torsional moment per unit normal force, metres (0 = point contact).
        reference: direction the first cone edge leans to (e.g. the grasp's approach axis).
    """
    forces = friction_cone(inward, mu, edges, reference)
    arm = point - centroid
    wrenches = [np.concatenate([f, np.cross(arm, f) / radius]) for f in forces]
    if torsion > 0:
        n = inward / np.linalg.norm(inward)
        for sign in (1.0, -1.0):
            wrenches.append(np.concatenate([n, (np.cross(arm, n) + sign * torsion * n) / radius]))
    return np.stack(wrenches)


def hull_margin(wrenches: np.ndarray) -> float:
    """Distance from the origin to the boundary of the convex hull of wrenches (M, 6); 0 unless the origin is
    strictly inside (including when the hull is flat, i.e. not of full dimension).

    Example:
        >>> round(hull_margin(np.vstack([np.eye(6), -np.eye(6)])), 6)  # the cross-polytope: 1/sqrt(6)
        0.408248
    """
    try:
        hull = ConvexHull(wrenches)
    except (QhullError, ValueError):
        return 0.0
    offsets = hull.equations[:, -1]  # facets are normal . x + offset <= 0 inside, normals of unit length
    return float(-offsets.max()) if np.all(offsets < -1e-12) else 0.0


def object_radius(vertices: np.ndarray, centroid: np.ndarray) -> float:
    """Largest distance of a vertex from the centroid (the torque scale of conventions §6)."""
    return float(np.linalg.norm(vertices - centroid, axis=1).max())


def ferrari_canny(
    points: np.ndarray,
    inward: np.ndarray,
    centroid: np.ndarray,
    radius: float,
    mu: float = MU,
    edges: int = CONE_EDGES,
    torsion: float = TORSION,
    reference: np.ndarray | None = None,
) -> float:
    """Epsilon quality of contacts (K, 3) with inward normals (K, 3) on an object (centroid, radius); pass the
    grasp's approach axis as ``reference`` for a value independent of the world frame."""
    wrenches = np.concatenate(
        [
            contact_wrenches(p, n, centroid, radius, mu, edges, torsion, reference)
            for p, n in zip(points, inward, strict=True)
        ]
    )
    return hull_margin(wrenches)
