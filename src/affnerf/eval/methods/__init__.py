"""Methods scored by the evaluation protocol: AFF-NeRF and the baselines, each behind the same interface.

Importing this package registers the built-in methods in :mod:`affnerf.eval.registry`, in the order below (the
order of ``--method all`` and of the table's columns).
"""

# isort: skip_file
from affnerf.eval.methods import affnerf  # noqa: F401  (registers affnerf, pixelnerf, semantic-ray, gsnerf)
from affnerf.eval.methods import affnerf_fit  # noqa: F401
from affnerf.eval.methods import semantic_nerf  # noqa: F401
from affnerf.eval.methods import retrieval  # noqa: F401
from affnerf.eval.methods import constant  # noqa: F401
