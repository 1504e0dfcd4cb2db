"""Evaluation methods by name: each method module registers how it is built, and ``affnerf eval --method NAME``
looks it up here (as nerfstudio's method configs are looked up by name).

Add a method by writing a class with the :class:`~affnerf.eval.protocol.Method` interface in
``eval/methods/<name>.py``, registering a :class:`MethodSpec` at the bottom of that module, and importing the
module in ``eval/methods/__init__.py``.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from affnerf.data.dataset import Dataset
from affnerf.errors import AffnerfError
from affnerf.eval.protocol import Method


@dataclass(frozen=True)
class MethodContext:
    """What building a method may use.

    Attributes:
        dataset: the evaluated dataset (baselines that need training objects read them here).
        run: the trained run given to ``affnerf eval --run``.
        device: ``auto``, ``cpu`` or ``cuda``.
        chunk: rays per forward pass.
        fast: render with the objects' occupancy grids (empty-space skipping).
        semantic_steps: optimisation steps of each per-object Semantic-NeRF.
        mesh_resolution: marching-cubes samples per axis of the meshes methods extract for the 3D metrics.
    """

    dataset: Dataset
    run: Path
    device: str
    chunk: int
    fast: bool
    semantic_steps: int
    mesh_resolution: int = 128


@dataclass(frozen=True)
class MethodSpec:
    """A registered method.

    Attributes:
        name: what ``--method`` calls it.
        build: makes the method from a context (loading any run it needs).
        summary: one line for ``--help`` and error messages.
        in_all: whether ``--method all`` includes it.
    """

    name: str
    build: Callable[[MethodContext], Method]
    summary: str
    in_all: bool = True


_METHODS: dict[str, MethodSpec] = {}


def register_method(spec: MethodSpec) -> MethodSpec:
    """Make ``spec`` available by its name; a second method under a taken name is an error (the same source
    imported again, as doctest collection may do, replaces its earlier registration)."""
    taken = _METHODS.get(spec.name)
    if taken is not None and _source(taken.build) != _source(spec.build):
        raise ValueError(f"evaluation method {spec.name!r} is registered twice")
    _METHODS[spec.name] = spec
    return spec


def _source(build: Callable) -> tuple[str, int] | None:
    """Where a builder is defined (file, line), or None when that cannot be told."""
    code = getattr(build, "__code__", None)
    return None if code is None else (code.co_filename, code.co_firstlineno)


def method_names() -> list[str]:
    """Registered names, in registration order."""
    return list(_METHODS)


def method_spec(name: str) -> MethodSpec:
    """The spec registered under ``name``.

    Raises:
        AffnerfError: for an unknown name, listing the known ones.
    """
    if name not in _METHODS:
        raise AffnerfError(f"unknown method {name!r} (known: {', '.join(_METHODS)})")
    return _METHODS[name]


_VIEWS_SUFFIX = re.compile(r"^(?P<name>.+)-(?P<views>[0-9]+)v$")


def parse_methods(text: str) -> list[str]:
    """Method names from ``a,b`` or ``all`` (every method with ``in_all``), each checked against the registry (a
    ``-<N>v`` suffix, see :func:`parse_method_views`, is dropped)."""
    return [name for name, _ in parse_method_views(text)]


def parse_method_views(text: str) -> list[tuple[str, int | None]]:
    """Methods and the input views each is given, from ``a,b-3v`` or ``all``.

    A name with a ``-<N>v`` suffix is that method given N input views, and its results are filed under that label
    (``pixelnerf-3v``); a bare name is given the evaluation's ``--input-views`` (None here). ``all`` is every method
    with ``in_all``, bare.

    Example:
        >>> import affnerf.eval.methods
        >>> parse_method_views("affnerf, pixelnerf-3v")
        [('affnerf', None), ('pixelnerf', 3)]

    Raises:
        AffnerfError: for an unknown name or a suffix of 0 views.
    """
    if text.strip() == "all":
        return [(name, None) for name, spec in _METHODS.items() if spec.in_all]
    return [_method_views(t.strip()) for t in text.split(",") if t.strip()]


def _method_views(token: str) -> tuple[str, int | None]:
    """One ``--method`` entry: a registered name as it is, else ``<name>-<N>v``."""
    match = _VIEWS_SUFFIX.match(token)
    if token in _METHODS or match is None:
        return method_spec(token).name, None
    views = int(match["views"])
    if views < 1:
        raise AffnerfError(f"--method {token!r}: a method is given at least 1 input view")
    return method_spec(match["name"]).name, views
