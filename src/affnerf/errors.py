"""User-facing errors.

Anything a user can cause (a corrupt image, a missing file, a NaN in a pose, an unknown label) raises
:class:`AffnerfError` with one line that names the file and the problem. The CLI prints that line and exits
with code 2; ``--debug`` shows the traceback instead.
"""

from __future__ import annotations

from os import PathLike


class AffnerfError(Exception):
    """An error caused by input, reported to users as one line (CLI exit code 2)."""


def input_error(path: str | PathLike[str] | None, problem: str) -> AffnerfError:
    """Build an :class:`AffnerfError` of the form ``"<path>: <problem>"``.

    Args:
        path: The file or folder at fault (``None`` when no file is involved).
        problem: What is wrong, in a few words; newlines are folded so the message stays on one line.

    Example:
        >>> str(input_error("a/rgb/000.png", "not a PNG image"))
        'a/rgb/000.png: not a PNG image'
    """
    text = " ".join(str(problem).split())
    return AffnerfError(text if path is None else f"{path}: {text}")
