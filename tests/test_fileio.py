"""Atomic writes keep the old file on failure and give normal permissions; JSON reads fail in one line."""

from __future__ import annotations

import os

import pytest

from affnerf.errors import AffnerfError
from affnerf.fileio import atomic_write, read_json_file


def test_failed_write_keeps_the_previous_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "a.bin"
    atomic_write(target, lambda f: f.write(b"old"))

    def broken(f):
        f.write(b"half")
        raise OSError("disk full")

    with pytest.raises(OSError):
        atomic_write(target, broken)
    assert target.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["a.bin"]


def test_written_file_is_readable_by_others_under_a_usual_umask(tmp_path):
    old = os.umask(0o022)
    try:
        path = atomic_write(tmp_path / "b.json", lambda f: f.write(b"{}"))
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize(
    ("content", "problem"), [(None, "file not found"), (b"{nope", "not valid JSON"), (b"\xff\xfe", "not valid JSON")]
)
def test_bad_json_files_name_the_file(tmp_path, content, problem):
    path = tmp_path / "c.json"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(AffnerfError, match=problem) as info:
        read_json_file(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_json_files_are_strict_json_with_null_for_non_finite_numbers(tmp_path):
    import json

    import numpy as np

    from affnerf.fileio import write_json_atomic

    path = tmp_path / "metrics.json"
    write_json_atomic(path, {"mIoU": float("nan"), "PSNR": np.float64(np.inf), "PA": np.float32(0.25)})
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads(text) == {"mIoU": None, "PSNR": None, "PA": 0.25}
