"""One CoACD decomposition in a process of its own (``python -m affnerf.grasp.coacd_worker``), used by
:mod:`affnerf.grasp.convex`.

CoACD can abort the whole process on some meshes (``std::logic_error: unexpected code path was hit``, a C++
exception Python cannot catch), which would end an hour-long evaluation with nothing written. Run here, such a
failure only ends this child. It reads a pickled ``(vertices, faces, kwargs)`` on stdin and writes a pickled list of
each convex part's vertices on stdout; it imports nothing but numpy and CoACD, so it starts in well under a second.
"""

from __future__ import annotations

import os
import pickle
import sys

import numpy as np


def decompose(vertices: np.ndarray, faces: np.ndarray, kwargs: dict) -> list[np.ndarray]:
    """The vertices of each convex part CoACD finds for the mesh (``kwargs``: :func:`coacd.run_coacd`'s options)."""
    import coacd

    coacd.set_log_level("error")
    raw = coacd.run_coacd(coacd.Mesh(np.asarray(vertices, np.float64), np.asarray(faces, np.int32)), **kwargs)
    return [np.asarray(part_vertices, np.float64) for part_vertices, _ in raw]


def main() -> None:
    vertices, faces, kwargs = pickle.load(sys.stdin.buffer)
    with os.fdopen(os.dup(1), "wb") as result:
        os.dup2(2, 1)  # whatever CoACD prints goes to stderr, not into the result
        result.write(pickle.dumps(decompose(vertices, faces, kwargs)))


if __name__ == "__main__":
    main()
