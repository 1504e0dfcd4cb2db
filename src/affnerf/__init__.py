"""affnerf: 3D affordance models of objects from one image.

The package reads the way data flows: ``objects`` (part-annotated meshes) -> ``data`` (multi-view datasets)
-> ``model`` -> ``train`` -> ``predict`` -> ``grasp`` -> ``eval``, with ``rendering``, ``metrics`` and ``pictures``
as shared tools and ``cli`` on top; every CLI verb (``affnerf <verb>``) is a thin layer over the Python API.
``docs/architecture.md`` says what each package owns; ``docs/conventions.md`` holds the contracts (frames, dataset
format, vocabulary, metrics, grasps), cited in docstrings as "conventions §N".
"""

__version__ = "0.1.0"
