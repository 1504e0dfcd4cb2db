"""Pictures for people, in one place: composing arrays (:mod:`~affnerf.pictures.compose`), meshes seen from a few
sides (:mod:`~affnerf.pictures.meshes`) and contact sheets of datasets and demo outputs
(:mod:`~affnerf.pictures.sheets`). It sits just above ``data`` (it ray-casts meshes and reads datasets), so
training, prediction, grasps, evaluation and the demo can all draw with it. The interactive 3D viewer is
``affnerf.viewer``.
"""
