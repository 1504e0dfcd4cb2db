"""``affnerf view``: a web viewer of a prediction folder, a dataset object or a mesh."""

from __future__ import annotations

from pathlib import Path

from tyro.conf import Positional


def view(path: Positional[Path], port: int = 8080, host: str = "127.0.0.1", top_k: int = 5) -> None:
    """Show an output folder or a mesh in the browser (a viser web viewer), until Ctrl-C.

    The mesh is coloured by affordance, one class per layer with a checkbox and a legend (surface areas); the
    grasps (grasps.json in the folder, in its grasps/ subfolder or beside the mesh) are drawn as gripper models,
    the best one dark; the input image is shown with its camera (for a prediction, which is pose-free, a
    stand-in at the first turntable camera; for a dataset object folder, frame 0's real camera).

    Args:
        path: a prediction folder, a dataset object folder, a grasps folder, or a mesh (PLY, GLB, OBJ).
        port: port to serve on (the next free one is taken when it is busy; the URL printed is right).
        host: address to listen on; 127.0.0.1 serves this machine only, 0.0.0.0 every network interface.
        top_k: grasps shown at first, best first.
    """
    from affnerf.viewer.server import serve

    serve(path, host=host, port=port, block=True, top_k=top_k)
