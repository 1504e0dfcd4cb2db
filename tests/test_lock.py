"""requirements-lock.txt, the exact versions ``make install`` installs by default: it pins every dependency
pyproject.toml names (torch excepted: the Makefile pins it), each to one version that the requirement allows."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]


def _lock() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "requirements-lock.txt").read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            name, version = line.split("==")
            pins[canonicalize_name(name)] = version.strip()
    return pins


def test_every_dependency_is_pinned_to_a_version_it_allows():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    requirements = [Requirement(r) for r in project["dependencies"]]
    requirements += [Requirement(r) for extra in ("dev", "segment") for r in project["optional-dependencies"][extra]]
    pins = _lock()
    for requirement in requirements:
        name = canonicalize_name(requirement.name)
        if name == "torch":
            assert name not in pins  # the Makefile installs the CPU build by its own pin
            continue
        assert name in pins, f"requirements-lock.txt does not pin {requirement.name}"
        assert requirement.specifier.contains(pins[name], prereleases=True), f"{name}=={pins[name]} vs {requirement}"


def test_make_install_uses_the_lock_unless_told_not_to():
    makefile = (ROOT / "Makefile").read_text()
    assert re.search(r"^LOCK \?= requirements-lock\.txt$", makefile, re.MULTILINE)
    assert makefile.count("$(CONSTRAINTS)") == 2  # torch's install and the package's
