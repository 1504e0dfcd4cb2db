"""Metrics shared by training (validation) and evaluation: pure functions on arrays, below both.

- :mod:`affnerf.metrics.segmentation`: confusion matrices and mIoU / PA / MPA of label maps.
- :mod:`affnerf.metrics.image`: PSNR of rendered colour.
- :mod:`affnerf.metrics.surface`: 3D metrics of labelled meshes (Chamfer-L1, F-score at 1 cm, 3D affordance mIoU).
"""
