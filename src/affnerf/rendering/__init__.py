"""Volume rendering as small pure functions on tensors: rays, samplers and the quadrature of NeRF.

Shapes use R for rays, S for samples along a ray, C for channels or classes.
"""
