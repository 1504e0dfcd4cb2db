"""The affordance vocabulary (conventions §3): fixed ids, names and display colours."""

from __future__ import annotations

import numpy as np

from affnerf.errors import AffnerfError

#: Class names indexed by id. Id 0 is the background; the ids are a contract and never change.
AFFORDANCE_CLASSES: tuple[str, ...] = (
    "background",
    "grasp",
    "cut",
    "screw",
    "write",
    "open",
    "pull",
    "pour",
    "contain",
    "wear",
    "view",
    "support",
)

#: Display colour (RGB, uint8) of each class, chosen to stay distinct on white and on object colours.
AFFORDANCE_PALETTE: np.ndarray = np.array(
    [
        (0, 0, 0),  # background
        (230, 25, 75),  # grasp: red
        (60, 180, 75),  # cut: green
        (255, 200, 25),  # screw: yellow
        (0, 130, 200),  # write: blue
        (245, 130, 48),  # open: orange
        (145, 30, 180),  # pull: purple
        (70, 240, 240),  # pour: cyan
        (240, 50, 230),  # contain: magenta
        (170, 110, 40),  # wear: brown
        (128, 128, 255),  # view: lavender blue
        (128, 128, 128),  # support: grey
    ],
    dtype=np.uint8,
)

_IDS = {name: i for i, name in enumerate(AFFORDANCE_CLASSES)}


def affordance_id(name: str) -> int:
    """Id of an affordance name.

    Raises:
        AffnerfError: if ``name`` is not in the vocabulary.

    Example:
        >>> affordance_id("pull")
        6
    """
    try:
        return _IDS[name]
    except KeyError:
        known = ", ".join(AFFORDANCE_CLASSES[1:])
        raise AffnerfError(f"unknown affordance {name!r} (known: {known})") from None


def colorize_labels(labels: np.ndarray) -> np.ndarray:
    """Map class ids to display colours.

    Args:
        labels: (...) integer class ids; ids past the palette wrap around.

    Returns:
        (..., 3) uint8 colours, background black.

    Example:
        >>> colorize_labels(np.array([0, 1])).tolist()
        [[0, 0, 0], [230, 25, 75]]
    """
    ids = np.asarray(labels, dtype=np.int64)
    return AFFORDANCE_PALETTE[np.mod(ids, len(AFFORDANCE_PALETTE))]
