"""Convex decomposition for physics: CoACD runs in a child process, so that when it aborts, hangs or answers
garbage only that piece falls back to its hull, and the evaluation around it goes on; closed pieces skip CoACD's own
manifold check (which aborts on some closed meshes)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import trimesh
from shapely.geometry import Polygon

from affnerf.grasp import convex
from affnerf.grasp.convex import coacd_parts, convex_parts


def _l_shape(size: float) -> trimesh.Trimesh:
    """A closed non-convex L-shaped prism; a different ``size`` gives a different cache key."""
    outline = np.array([(0, 0), (1, 0), (1, 0.3), (0.3, 0.3), (0.3, 1), (0, 1)]) * size
    return trimesh.creation.extrude_polygon(Polygon(outline), 0.3 * size)


def test_worker_returns_the_vertices_of_convex_parts():
    parts = coacd_parts(_l_shape(0.1), threshold=0.08, max_convex_hull=16, preprocess_mode="off", seed=0)
    assert parts is not None and len(parts) >= 2
    assert all(isinstance(p, np.ndarray) and p.ndim == 2 and p.shape[1] == 3 for p in parts)


@pytest.mark.parametrize(
    "worker",
    [
        "import os; os.abort()",  # what CoACD's uncaught C++ exception does to its process
        "import sys; sys.exit(3)",
        "print('not a pickle')",
    ],
    ids=["abort", "error-exit", "garbage"],
)
def test_a_failing_worker_falls_back_to_the_hull_and_the_caller_survives(monkeypatch, worker):
    monkeypatch.setattr(convex, "WORKER", [sys.executable, "-c", worker])
    mesh = _l_shape(0.101)
    parts = convex_parts(mesh)
    assert len(parts) == 1
    assert parts[0].volume == pytest.approx(mesh.convex_hull.volume)


def test_a_hanging_worker_is_stopped_and_falls_back_to_the_hull(monkeypatch):
    monkeypatch.setattr(convex, "WORKER", [sys.executable, "-c", "import time; time.sleep(60)"])
    monkeypatch.setattr(convex, "WORKER_TIMEOUT", 1.0)
    mesh = _l_shape(0.102)
    assert coacd_parts(mesh, seed=0) is None
    assert len(convex_parts(mesh)) == 1


def test_closed_pieces_skip_coacds_manifold_check_and_open_meshes_are_remeshed(monkeypatch):
    modes = []

    def record(mesh, **kwargs):
        modes.append(kwargs["preprocess_mode"])
        return None

    monkeypatch.setattr(convex, "coacd_parts", record)
    convex_parts(_l_shape(0.103))
    closed = _l_shape(0.104)
    lidless = closed.faces[closed.face_normals[:, 2] < 0.5]  # the L-shaped top removed: an open cup
    convex_parts(trimesh.Trimesh(closed.vertices, lidless, process=False))
    assert modes == ["off", "on"]
