"""Evaluation: the protocol that reproduces the paper's Table 2 (conventions §5) with its methods and reports,
and the grasp study of Table 3."""
