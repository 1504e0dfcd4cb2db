"""A web viewer of predictions, dataset objects and meshes (``affnerf view``), built on viser.

:func:`serve` starts a server on PATH; :func:`build_scene` adds PATH's content to a viser server of your own.
``affnerf.viewer.headless.screenshot`` takes a screenshot of the page in headless Chromium (used by the tests).
"""

from affnerf.viewer.server import SceneHandles, ViewContent, build_scene, load_content, serve

__all__ = ["SceneHandles", "ViewContent", "build_scene", "load_content", "serve"]
