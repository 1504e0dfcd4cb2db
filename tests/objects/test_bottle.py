"""Bottle specifics: the cap is optional and closes the mouth; the shoulder closes onto the neck."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from affnerf.objects.asset import Material
from affnerf.objects.categories import bottle

MATS = (Material((0.2, 0.5, 0.2)), Material((0.9, 0.9, 0.8)), Material((0.1, 0.1, 0.6)))


def _params(seed: int, **changes) -> bottle.BottleParams:
    return replace(bottle.sample_params(np.random.default_rng(seed)), **changes)


@pytest.mark.parametrize("cap", ["screw", "capsule", "cork"])
def test_a_cap_closes_the_mouth_from_above(cap):
    parts = {part.name: part for part in bottle.build(_params(0, cap=cap), *MATS).parts}
    assert parts["cap"].affordance == "open"
    cap_lo, cap_hi = parts["cap"].mesh.bounds
    mouth_lo, mouth_hi = parts["mouth"].mesh.bounds
    assert cap_hi[2] > mouth_hi[2]
    assert cap_lo[2] < mouth_hi[2]  # it overlaps the mouth rather than floating above it
    assert parts["cap"].mesh.bounds[1, 2] == pytest.approx(max(p.mesh.bounds[1, 2] for p in parts.values()))


def test_a_capless_bottle_has_no_open_part_and_ends_at_its_mouth():
    p = _params(1, cap="none")
    asset = bottle.build(p, *MATS)
    assert [part.name for part in asset.parts] == ["body", "neck", "mouth"]
    assert "open" not in {part.affordance for part in asset.parts}
    assert asset.bounds()[1, 2] == pytest.approx(bottle.neck_top(p))


@pytest.mark.parametrize("section, aspect", [("round", 1.0), ("round", 0.7), ("square", 1.0), ("square", 0.8)])
def test_body_is_upright_and_its_shoulder_closes_onto_the_neck(section, aspect):
    p = _params(2, section=section, aspect=aspect)
    body = bottle.build(p, *MATS).parts[0].mesh
    v = body.vertices
    assert v[:, 2].min() == pytest.approx(0.0)  # standing on its base at z = 0
    top = v[np.isclose(v[:, 2], v[:, 2].max())]
    radii = np.hypot(top[:, 0], top[:, 1])
    np.testing.assert_allclose(radii[radii > 1e-9], p.neck_radius, rtol=1e-6)  # a circle of the neck's radius
    ring_z = v[np.argmin(np.abs(v[:, 2] - 0.5 * p.wall_height)), 2]
    ring = v[v[:, 2] == ring_z]  # the section half-way up the wall
    assert np.ptp(ring[:, 1]) / np.ptp(ring[:, 0]) == pytest.approx(aspect)
