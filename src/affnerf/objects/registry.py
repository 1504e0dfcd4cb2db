"""The procedural categories and the one entry point that makes an object from a category and a seed."""

from __future__ import annotations

import importlib
from collections.abc import Callable

import numpy as np

from affnerf.errors import AffnerfError
from affnerf.objects.asset import ObjectAsset, canonicalize

#: The procedural categories, in a fixed order (it is part of how seeds map to objects).
CATEGORY_NAMES: tuple[str, ...] = (
    "screwdriver",
    "pen",
    "scissors",
    "eyeglasses",
    "bucket",
    "bottle",
    "cabinet",
    "teapot",
)


def category_generator(category: str) -> Callable[[np.random.Generator], ObjectAsset]:
    """The ``generate(rng)`` function of a procedural category.

    Raises:
        AffnerfError: for a name that is not a procedural category.
    """
    if category not in CATEGORY_NAMES:
        raise AffnerfError(f"unknown category {category!r} (known: {', '.join(CATEGORY_NAMES)})")
    module = importlib.import_module(f"affnerf.objects.categories.{category}")
    return module.generate


def parse_categories(text: str) -> list[str]:
    """Parse ``all`` or a comma-separated list of category names, keeping the registry's order.

    Example:
        >>> parse_categories("pen,screwdriver")
        ['screwdriver', 'pen']
    """
    if text.strip() in ("", "all"):
        return list(CATEGORY_NAMES)
    names = [t.strip() for t in text.split(",") if t.strip()]
    for name in names:
        category_generator(name)  # validates
    return [c for c in CATEGORY_NAMES if c in names]


def object_seed(seed: int, category: str, index: int) -> np.random.SeedSequence:
    """The seed sequence of object ``index`` of ``category`` in a dataset generated with ``seed``.

    It depends on nothing else, so an object is the same whichever shard or worker makes it.
    """
    return np.random.SeedSequence([int(seed), CATEGORY_NAMES.index(category), int(index)])


def make_object(category: str, seed: int | np.random.SeedSequence) -> ObjectAsset:
    """Build one procedural object of ``category`` from ``seed``, centred and fitted into the canonical cube."""
    rng = np.random.default_rng(seed)
    return canonicalize(category_generator(category)(rng))
