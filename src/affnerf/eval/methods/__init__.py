"""Methods scored by the evaluation protocol: AFF-NeRF and the baselines, each behind the same interface.

Importing this package registers the built-in methods in :mod:`affnerf.eval.registry`, in this order.
"""

from affnerf.eval.methods import affnerf, semantic_nerf, retrieval, constant  # noqa: F401  (registration)
