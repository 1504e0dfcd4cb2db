"""The README's Python quickstart runs as written (with the shipped model) and its CLI verbs exist."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from affnerf.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def quickstart_python() -> str:
    """The first ```python block after the Quickstart heading."""
    section = README.split("## Quickstart", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.slow
def test_python_quickstart_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    scope: dict = {}
    exec(compile(quickstart_python(), "README.md:quickstart", "exec"), scope)
    view, mesh, grasps = scope["view"], scope["mesh"], scope["grasps"]
    assert view.rgb.shape == (300, 400, 3) and view.labels.shape == (300, 400)
    assert len(mesh.faces) > 100 and np.isfinite(mesh.vertices).all()
    assert grasps and all(g.epsilon >= 0 for g in grasps)


def test_every_verb_in_the_readme_has_help(capsys):
    verbs = set(re.findall(r"^(?:\.venv/bin/)?affnerf ([a-z]+)", README, re.M))
    assert {"data", "train", "predict", "eval", "metrics", "grasp", "view"} <= verbs
    for verb in sorted(verbs):
        with pytest.raises(SystemExit) as info:
            main([verb, "--help"])
        assert info.value.code == 0, verb
        assert os.linesep in capsys.readouterr().out
