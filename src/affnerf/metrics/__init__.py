"""Metrics shared by training (validation) and evaluation: pure functions on arrays, below both.

- :mod:`affnerf.metrics.segmentation`: confusion matrices and mIoU / PA / MPA of label maps.
- :mod:`affnerf.metrics.image`: PSNR of rendered colour.
"""
