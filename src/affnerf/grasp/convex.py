"""Convex decompositions of meshes for physics (CoACD), cached, and the mass properties of their union."""

from __future__ import annotations

import hashlib
import pickle
import subprocess
import sys
from collections import OrderedDict

import numpy as np
import trimesh

from affnerf.errors import AffnerfError

_MAX_PIECES = 256  #: meshes with more connected pieces than this are decomposed as a whole
_CACHE_SIZE = 64  #: decompositions kept by :func:`convex_parts`
_CACHE: OrderedDict[str, tuple[trimesh.Trimesh, ...]] = OrderedDict()
#: The command that runs one CoACD decomposition in a child process (:mod:`affnerf.grasp.coacd_worker`).
WORKER = [sys.executable, "-m", "affnerf.grasp.coacd_worker"]
WORKER_TIMEOUT = 600.0  #: seconds one decomposition may take before its piece falls back to the hull


def convex_parts(mesh: trimesh.Trimesh, threshold: float = 0.08, max_parts: int = 16) -> list[trimesh.Trimesh]:
    """Convex decomposition of ``mesh`` (metres; closed or open, possibly a union of parts) with CoACD, cached
    per mesh content and settings; returns convex meshes in the mesh frame (copies, safe to modify).

    When every connected piece is closed (as given, or after merging duplicate vertices), each piece is
    decomposed on its own, else the mesh as a whole (CoACD remeshes it). A piece that is nearly convex, small or
    that CoACD fails on becomes its convex hull; flat pieces are dropped. CoACD runs in a child process
    (:func:`coacd_parts`), so that when it aborts (it does on some meshes) only that piece falls back to its hull.
    A typical object (0.1-0.44 m, a few thousand faces) takes well under a few seconds, a large thin-walled one
    (30k faces) ten or more.

    Args:
        mesh: the mesh.
        threshold: CoACD's concavity threshold, relative to a piece's size (larger: fewer, coarser parts).
        max_parts: at most this many convex parts per piece.

    Raises:
        AffnerfError: the mesh is empty, has non-finite vertices, or encloses no volume at all.
    """
    if len(mesh.faces) == 0 or not np.all(np.isfinite(mesh.vertices)):
        raise AffnerfError("lift test: the mesh is empty or has non-finite vertices")
    digest = hashlib.sha1(np.ascontiguousarray(mesh.vertices, np.float64).tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, np.int64).tobytes())
    key = f"{digest.hexdigest()}:{threshold}:{max_parts}"
    if key not in _CACHE:
        _CACHE[key] = tuple(_decompose(mesh, threshold, max_parts))
        if len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    _CACHE.move_to_end(key)
    return [part.copy() for part in _CACHE[key]]


def _decompose(mesh: trimesh.Trimesh, threshold: float, max_parts: int) -> list[trimesh.Trimesh]:
    """Uncached body of :func:`convex_parts`."""
    pieces = [mesh]
    merged = mesh.copy()
    merged.merge_vertices()
    for candidate in (mesh, merged):
        split = candidate.split(only_watertight=False)
        if 0 < len(split) <= _MAX_PIECES and all(piece.is_watertight for piece in split):
            pieces = split
            break
    size = float(np.max(mesh.extents))
    parts = [part for piece in pieces for part in _decompose_piece(piece, threshold, max_parts, size)]
    if not parts:
        raise AffnerfError("lift test: the mesh encloses no volume")
    return parts


def _hull(vertices: np.ndarray) -> trimesh.Trimesh | None:
    """Convex hull of points, or None when they are flat or degenerate."""
    try:
        with np.errstate(divide="ignore", invalid="ignore"):
            hull = trimesh.Trimesh(vertices=np.asarray(vertices, float)).convex_hull
            return hull if hull.volume > 0.0 else None
    except Exception:  # noqa: BLE001 - qhull rejects flat or tiny point sets
        return None


def _decompose_piece(piece: trimesh.Trimesh, threshold: float, max_parts: int, size: float) -> list[trimesh.Trimesh]:
    """Convex parts of one piece: its hull when it nearly fills it, is under 5% of ``size`` or CoACD fails."""
    hull = _hull(piece.vertices)
    if hull is None:
        return []
    convex = piece.is_volume and piece.volume >= 0.98 * hull.volume
    if convex or len(piece.faces) < 8 or np.max(piece.extents) < 0.05 * size:
        return [hull]
    raw = coacd_parts(
        piece,
        threshold=threshold,
        max_convex_hull=max_parts,
        # CoACD's "auto" mode checks manifoldness itself, and that check aborts on some closed meshes (a bottle of
        # the procedural test split): a closed piece needs no remeshing, an open mesh does
        preprocess_mode="off" if piece.is_watertight else "on",
        preprocess_resolution=40,
        resolution=1000,
        mcts_nodes=10,
        mcts_iterations=30,
        mcts_max_depth=2,
        seed=0,
    )
    if raw is None:
        return [hull]
    parts = [part for part in (_hull(vertices) for vertices in raw if len(vertices) >= 4) if part is not None]
    return parts or [hull]


def coacd_parts(mesh: trimesh.Trimesh, **kwargs: object) -> list[np.ndarray] | None:
    """The vertices of each convex part CoACD finds for ``mesh`` (``kwargs``: :func:`coacd.run_coacd`'s options),
    computed in a child process (:data:`WORKER`); None when CoACD fails, aborts or takes over
    :data:`WORKER_TIMEOUT` seconds."""
    request = pickle.dumps(
        (np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int32), kwargs), pickle.HIGHEST_PROTOCOL
    )
    try:
        done = subprocess.run(WORKER, input=request, capture_output=True, timeout=WORKER_TIMEOUT, check=False)
    except (OSError, subprocess.TimeoutExpired):
        return None
    if done.returncode != 0:
        return None
    try:
        parts = pickle.loads(done.stdout)  # noqa: S301 - our own child's answer
    except Exception:  # noqa: BLE001 - a truncated or garbled answer counts as a failure
        return None
    return parts if isinstance(parts, list) else None


def mass_properties(parts: list[trimesh.Trimesh], mass: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre of mass (3,), principal moments of inertia (3,) and principal axes (3x3 rotation, as columns) of a
    uniform solid of ``mass`` filling the convex ``parts`` (where parts overlap, they count twice)."""
    solid = trimesh.util.concatenate(parts)
    if not solid.volume > 0.0:
        raise AffnerfError("lift test: the mesh encloses no volume")
    moments, axes = np.linalg.eigh(solid.moment_inertia * (mass / solid.volume))
    if np.linalg.det(axes) < 0.0:
        axes[:, 0] = -axes[:, 0]
    return np.asarray(solid.center_mass, float), np.maximum(moments, 1e-12), axes
