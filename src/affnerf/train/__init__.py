"""Training AFF-NeRF: configurations, frame caches, the paper's ray sampler, checkpoints and the loop, on one CPU,
one GPU or many under ``torchrun``."""
