"""Invariants every procedural category keeps (conventions §1, §3)."""

from __future__ import annotations

import numpy as np
import pytest

from affnerf.objects.asset import CANONICAL_HALF_EXTENT
from affnerf.objects.registry import CATEGORY_NAMES, make_object, object_seed

#: Affordances each category's parts may carry, and those every object of it must have (conventions §3).
ALLOWED = {
    "screwdriver": {"grasp", "screw"},
    "pen": {"grasp", "open", "write"},
    "scissors": {"grasp", "cut"},
    "eyeglasses": {"grasp", "wear", "view"},
    "bucket": {"grasp", "contain"},
    "bottle": {"grasp", "pour", "open"},
    "cabinet": {"pull", "open", "support"},
    "teapot": {"grasp", "pour", "open", "contain"},
}
REQUIRED = {
    "screwdriver": {"grasp", "screw"},
    "pen": {"grasp", "write"},
    "scissors": {"grasp", "cut"},
    "eyeglasses": {"grasp", "wear", "view"},
    "bucket": {"grasp", "contain"},
    "bottle": {"grasp", "pour"},
    "cabinet": {"pull", "open", "support"},
    "teapot": {"grasp", "pour", "contain"},
}
SEEDS = range(6)


@pytest.fixture(scope="module", params=CATEGORY_NAMES)
def objects(request):
    category = request.param
    return category, [make_object(category, object_seed(0, category, i)) for i in SEEDS]


def test_parts_are_closed_oriented_surfaces(objects):
    category, assets = objects
    for asset in assets:
        for part in asset.parts:
            mesh = part.mesh
            assert np.isfinite(mesh.vertices).all(), (category, part.name)
            assert mesh.is_watertight, (category, part.name)
            assert mesh.is_winding_consistent, (category, part.name)
            assert mesh.volume > 0, (category, part.name)


def test_objects_fit_the_canonical_cube_centred(objects):
    _, assets = objects
    for asset in assets:
        lo, hi = asset.bounds()
        assert np.all(np.abs(lo) <= CANONICAL_HALF_EXTENT) and np.all(np.abs(hi) <= CANONICAL_HALF_EXTENT)
        np.testing.assert_allclose((lo + hi) / 2, 0.0, atol=1e-9)


def test_affordances_follow_the_vocabulary_table(objects):
    category, assets = objects
    for asset in assets:
        present = {p.affordance for p in asset.parts}
        assert present <= ALLOWED[category], present
        assert REQUIRED[category] <= present, present


def test_same_seed_same_object(objects):
    category, assets = objects
    again = make_object(category, object_seed(0, category, 0))
    assert [p.name for p in again.parts] == [p.name for p in assets[0].parts]
    for a, b in zip(again.parts, assets[0].parts, strict=True):
        np.testing.assert_array_equal(a.mesh.vertices, b.mesh.vertices)
        assert a.materials == b.materials


def test_real_variety(objects):
    """At least five continuous shape parameters vary, a discrete style varies, and so do the shapes."""
    category, assets = objects
    many = assets + [make_object(category, object_seed(1, category, i)) for i in range(14)]
    params = [a.params for a in many]
    continuous = [k for k, v in params[0].items() if isinstance(v, float)]
    varying = [k for k in continuous if np.std([p[k] for p in params]) > 1e-6]
    assert len(varying) >= 5, varying
    discrete = [k for k, v in params[0].items() if isinstance(v, (str, bool, int)) and not isinstance(v, float)]
    assert any(len({str(p[k]) for p in params}) >= 2 for k in discrete), discrete
    extents = np.array([np.sort(np.diff(a.bounds(), axis=0)[0]) for a in many])
    ratios = extents[:, :2] / extents[:, 2:]
    assert np.ptp(ratios[:, 1]) > 0.02 or np.ptp(ratios[:, 0]) > 0.02
    colors = {a.parts[0].materials[0].color for a in many}
    assert len(colors) > len(many) // 2


def test_articulated_states_are_recorded_within_limits():
    assets = [make_object("cabinet", object_seed(0, "cabinet", i)) for i in SEEDS]
    values = []
    for asset in assets:
        assert asset.joints
        names = {p.name for p in asset.parts}
        for joint in asset.joints:
            assert joint.lower <= joint.value <= joint.upper
            assert set(joint.parts) <= names and joint.parts
            values.append(joint.value)
    assert np.ptp(values) > 0
    assert not any(make_object(c, object_seed(0, c, 0)).joints for c in CATEGORY_NAMES if c != "cabinet")
