"""The evaluation-method registry: names, ``all``, unknown names, and a method added from outside."""

from __future__ import annotations

import pytest

import affnerf.eval.methods  # noqa: F401  (registers the built-in methods)
from affnerf.errors import AffnerfError
from affnerf.eval import registry
from affnerf.eval.methods.constant import ConstantMethod
from affnerf.eval.registry import (
    MethodContext,
    MethodSpec,
    method_names,
    parse_method_views,
    parse_methods,
    register_method,
)


def test_builtin_methods_are_registered_in_order():
    expected = [
        "affnerf",
        "pixelnerf",
        "pose-aware",
        "semantic-ray",
        "gsnerf",
        "affnerf-fit",
        "semantic-nerf",
        "retrieval",
        "constant",
    ]
    assert method_names()[:9] == expected


def test_all_leaves_out_the_constant_floor_and_the_fitted_affnerf():
    everything = ["affnerf", "pixelnerf", "pose-aware", "semantic-ray", "gsnerf", "semantic-nerf", "retrieval"]
    assert parse_methods("all") == everything
    assert parse_methods("semantic-ray,gsnerf") == ["semantic-ray", "gsnerf"]
    assert parse_methods(" retrieval , constant ") == ["retrieval", "constant"]


def test_a_views_suffix_gives_a_method_its_own_input_views():
    assert parse_method_views("affnerf, pixelnerf-3v,semantic-nerf-20v") == [
        ("affnerf", None),
        ("pixelnerf", 3),
        ("semantic-nerf", 20),
    ]
    assert parse_methods("gsnerf-3v,retrieval") == ["gsnerf", "retrieval"]
    assert parse_method_views("all") == [(name, None) for name in parse_methods("all")]
    with pytest.raises(AffnerfError, match="unknown method 'nerfacto'"):
        parse_method_views("nerfacto-3v")
    with pytest.raises(AffnerfError, match="at least 1 input view"):
        parse_method_views("pixelnerf-0v")


def test_unknown_method_names_the_known_ones():
    with pytest.raises(AffnerfError, match=r"unknown method 'nerfacto' \(known: affnerf, pixelnerf"):
        parse_methods("affnerf,nerfacto")


def test_a_registered_method_is_built_by_name(tmp_path):
    spec = MethodSpec("constant-grasp", lambda context: ConstantMethod(1), "grasp everywhere", in_all=False)
    register_method(spec)
    try:
        register_method(spec)  # the same definition again (a module imported twice) is not a clash
        with pytest.raises(ValueError, match="registered twice"):
            register_method(MethodSpec("constant-grasp", lambda context: ConstantMethod(2), "another"))
        assert "constant-grasp" in parse_methods("constant-grasp")
        context = MethodContext(None, tmp_path, "cpu", 64, True, 1)  # type: ignore[arg-type]
        method = registry.method_spec("constant-grasp").build(context)
        assert method.name == "constant-1"
        assert "constant-grasp" not in parse_methods("all")
    finally:
        registry._METHODS.pop("constant-grasp", None)
