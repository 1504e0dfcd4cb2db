"""affnerf: 3D affordance models of objects from one image.

The package reads the way data flows: ``objects`` (part-annotated meshes) -> ``data`` (multi-view datasets)
-> model, training, prediction, export, grasps and evaluation. Every CLI verb (``affnerf <verb>``) is a thin
layer over the Python API of these packages.
"""

__version__ = "0.1.0"
