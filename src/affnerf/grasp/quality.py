"""The Ferrari-Canny epsilon quality on the L1 grasp wrench space (conventions §6), as small pure functions.

Each contact pushes into the object along its inward normal with unit normal force; friction (coefficient mu) is
a cone linearised by ``edges`` directions; a soft finger adds a torsional moment about the normal of at most
``torsion`` metres times the normal force. Torques are divided by the object's radius (largest vertex distance
from the centroid) so forces and torques are comparable. The L1 wrench space is the convex hull of every
contact's primitive wrenches; epsilon is the distance from the origin to its boundary, and 0 when the origin is
not strictly inside.

Holding against gravity is a narrower question than epsilon's "every direction at once" (Dex-Net 3.0 calls it
wrench resistance): the object's weight acts at its centre of mass, so a grasp holds it when a pure upward force,
with no torque about that centre, lies in the wrench space. :func:`resisted_scale` is how far the space reaches
along such a direction (the largest weight, in units of the total normal force, the contacts can carry), and
:func:`hold_quality` the least of it while the object turns about the closing axis, as the disturbance of the
lift-and-disturb test turns it. Forces count, torques do not scale it: the value does not depend on ``radius``.
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


def wrench_space(wrenches: np.ndarray) -> np.ndarray | None:
    """(F, 7) facets ``normal . x + offset <= 0`` of the convex hull of wrenches (M, 6) and the origin (the L1
    wrench space of forces that may also be zero); None when that hull is flat (not of full dimension)."""
    try:
        return ConvexHull(np.vstack([wrenches, np.zeros((1, wrenches.shape[1]))])).equations
    except (QhullError, ValueError):
        return None


def resisted_scale(facets: np.ndarray, direction: np.ndarray) -> float:
    """Largest t >= 0 with ``t * direction`` (6,) inside the polytope of ``facets`` (F, 7) that holds the origin
    (:func:`wrench_space`); 0 when the origin lies on a facet the direction leaves through.

    Example:
        >>> cube = wrench_space(np.array(np.meshgrid(*[[-1.0, 1.0]] * 6)).reshape(6, -1).T)
        >>> round(resisted_scale(cube, np.array([0.0, 0.0, 0.5, 0, 0, 0])), 6)  # the face z = 1, at t = 2
        2.0
    """
    along = facets[:, :-1] @ direction
    with np.errstate(divide="ignore"):
        limits = np.where(along > 1e-12, -facets[:, -1] / np.where(along > 1e-12, along, 1.0), np.inf)
    return max(0.0, float(limits.min()))


def turned_up_directions(up: np.ndarray, axis: np.ndarray, angles_deg: tuple[float, ...]) -> np.ndarray:
    """(A, 6) pure-force wrenches that carry the weight while the object turns by each angle about ``axis``: the
    unit ``up`` (3,) rotated by minus each angle about the unit ``axis`` (3,) (Rodrigues), zero torque."""
    k = axis / np.linalg.norm(axis)
    out = []
    for angle in np.radians(angles_deg):
        c, s = np.cos(-angle), np.sin(-angle)
        u = up * c + np.cross(k, up) * s + k * (k @ up) * (1.0 - c)
        out.append(np.concatenate([u, np.zeros(3)]))
    return np.asarray(out)


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
    return hull_margin(grasp_wrenches(points, inward, centroid, radius, mu, edges, torsion, reference))


def grasp_wrenches(
    points: np.ndarray,
    inward: np.ndarray,
    centroid: np.ndarray,
    radius: float,
    mu: float = MU,
    edges: int = CONE_EDGES,
    torsion: float = TORSION,
    reference: np.ndarray | None = None,
) -> np.ndarray:
    """(K * (edges + 2), 6) primitive wrenches of contacts (K, 3) with inward normals (K, 3)
    (:func:`contact_wrenches` of each)."""
    return np.concatenate(
        [
            contact_wrenches(p, n, centroid, radius, mu, edges, torsion, reference)
            for p, n in zip(points, inward, strict=True)
        ]
    )


#: Turns of the object about the closing axis (degrees) that :func:`hold_quality` must hold through: upright, and
#: the lift-and-disturb test's ±90° with halfway points.
HOLD_TURNS = (-90.0, -45.0, 0.0, 45.0, 90.0)


def hold_quality(
    wrenches: np.ndarray, up: np.ndarray, axis: np.ndarray, turns: tuple[float, ...] = HOLD_TURNS
) -> float:
    """The least weight (in units of the total normal force) contacts with primitive wrenches (M, 6) carry at the
    centre of mass while the object turns by each of ``turns`` about the closing ``axis`` (3,) from ``up`` (3,),
    the object frame's vertical: :func:`resisted_scale` along :func:`turned_up_directions`; 0 when flat."""
    facets = wrench_space(wrenches)
    if facets is None:
        return 0.0
    return min(resisted_scale(facets, d) for d in turned_up_directions(up, axis, turns))
