"""Assets: canonical placement, merging parts, vocabulary checks."""

from __future__ import annotations

import numpy as np
import pytest

from affnerf.errors import AffnerfError
from affnerf.objects.asset import NORMALISED_EXTENT, Material, ObjectAsset, Part, canonicalize, merge_parts
from affnerf.objects.primitives import box, placed, translation


def _two_boxes():
    a = Part("handle", "grasp", placed(box((0.1, 0.02, 0.02)), translation((0.5, 1.0, 0.0))), (Material((1, 0, 0)),))
    b = Part("blade", "cut", placed(box((0.2, 0.01, 0.04)), translation((0.65, 1.0, 0.0))))
    return ObjectAsset("scissors", [a, b])


def test_canonicalize_centres_and_normalises_keeping_proportions():
    asset = _two_boxes()
    lo, hi = asset.bounds()
    out = canonicalize(asset)
    lo2, hi2 = out.bounds()
    np.testing.assert_allclose((lo2 + hi2) / 2, 0, atol=1e-12)
    assert np.isclose((hi2 - lo2).max(), NORMALISED_EXTENT)
    np.testing.assert_allclose((hi2 - lo2) / (hi - lo), out.scale)
    np.testing.assert_allclose(asset.bounds(), [lo, hi])  # the input is untouched


def test_merge_keeps_part_affordance_and_material_per_face():
    surface = merge_parts(_two_boxes())
    assert surface.faces.shape == (24, 3)
    assert surface.face_part.tolist() == [1] * 12 + [2] * 12
    assert surface.face_affordance.tolist() == [1] * 12 + [2] * 12
    assert surface.materials[surface.face_material[0]].color == (1, 0, 0)
    assert set(surface.vertex_part.tolist()) == {1, 2}


def test_unknown_affordance_and_repeated_names_are_refused():
    with pytest.raises(AffnerfError, match="unknown affordance"):
        Part("x", "fly", box((1, 1, 1)))
    with pytest.raises(AffnerfError, match="repeated part names"):
        ObjectAsset("toy", [Part("a", "grasp", box((1, 1, 1))), Part("a", "cut", box((1, 1, 1)))])
