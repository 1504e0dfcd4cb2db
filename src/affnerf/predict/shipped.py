"""The model shipped with affnerf (``MODEL_CARD.md`` says how it was trained)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from affnerf.errors import AffnerfError

SHIPPED_NAME = "affnerf-small.pt"


def shipped_model() -> Path:
    """The shipped checkpoint's path.

    Raises:
        AffnerfError: when this installation has none (then pass ``--run``).
    """
    path = Path(str(resources.files("affnerf.models").joinpath(SHIPPED_NAME)))
    if not path.is_file():
        raise AffnerfError(f"no --run given and no shipped model at {path}; train one with `affnerf train`")
    return path
