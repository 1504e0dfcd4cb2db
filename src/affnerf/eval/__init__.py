"""Evaluation: segmentation metrics (conventions §5) and the protocol that reproduces the paper's Table 2."""
