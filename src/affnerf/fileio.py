"""Files written atomically, JSON written atomically from numpy-bearing data, and JSON read with one-line errors.

A file written by :func:`atomic_write` appears under its final name only once completely written and synced; a
crash or a failed write (full disk, read-only folder) leaves the previous file, if any, untouched.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np

from affnerf.errors import input_error


def atomic_write(path: Path, write: Callable[[IO[bytes]], None]) -> Path:
    """Call ``write`` on a temporary binary file beside ``path``, sync it, then rename it to ``path``.

    Example:
        >>> import tempfile
        >>> target = Path(tempfile.mkdtemp()) / "note.txt"
        >>> atomic_write(target, lambda f: f.write(b"hello")).read_text()
        'hello'
        >>> oct(target.stat().st_mode & 0o777) == oct(0o666 & ~_umask())
        True
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the file the permissions open() would
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _umask() -> int:
    """The process's file-creation mask."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def read_json_file(path: Path) -> Any:
    """The parsed content of a JSON file.

    Raises:
        AffnerfError: naming the file, when it is missing or not valid JSON.
    """
    path = Path(path)
    if not path.is_file():
        raise input_error(path, "file not found")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise input_error(path, f"not valid JSON ({exc})") from None


def jsonable(value: Any) -> Any:
    """``value`` with numpy scalars and arrays, tuples and paths turned into plain JSON types, recursively; a
    non-finite number (a metric with nothing to average, an infinite PSNR) becomes ``None``, so the file is
    strict JSON (``null``) that any reader accepts.

    Example:
        >>> jsonable({"a": np.float32(0.5), "b": (1, float("nan")), "c": np.array([np.inf, 2.0])})
        {'a': 0.5, 'b': [1, None], 'c': [None, 2.0]}
    """
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    return value


def write_json_atomic(path: Path, data: Any) -> None:
    """Write JSON to ``path`` through a temporary file in the same folder and a rename.

    A crash or a failed write leaves the previous file untouched.
    """
    text = json.dumps(jsonable(data), indent=1, allow_nan=False).encode()
    atomic_write(Path(path), lambda f: f.write(text))
