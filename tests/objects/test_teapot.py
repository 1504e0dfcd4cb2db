"""Teapot specifics: the spout rises on +x above the widest point, the handle is on -x or over the lid."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from affnerf.objects.asset import Material
from affnerf.objects.categories import teapot

MATS = (Material((0.8, 0.8, 0.7)), Material((0.3, 0.2, 0.1)), Material((0.8, 0.8, 0.7)))


def _parts(p: teapot.TeapotParams) -> dict:
    return {part.name: part.mesh for part in teapot.build(p, *MATS).parts}


@pytest.mark.parametrize("seed", range(8))
def test_spout_tip_is_on_plus_x_and_above_the_widest_point(seed):
    p = teapot.sample_params(np.random.default_rng(seed))
    parts = _parts(p)
    body, spout = parts["body"].vertices, parts["spout"].vertices
    widest_z = body[np.argmax(np.hypot(body[:, 0], body[:, 1])), 2]
    tip = spout[np.argmax(spout[:, 0])]
    assert tip[0] > body[:, 0].max()  # sticks out of the body on the +x side
    assert tip[2] > widest_z
    assert spout[:, 0].min() > 0.0  # the whole spout is on the +x side
    assert body[:, 2].min() == pytest.approx(0.0)


@pytest.mark.parametrize("seed", range(4))
def test_side_handle_is_on_minus_x_and_a_top_handle_clears_the_lid(seed):
    p = teapot.sample_params(np.random.default_rng(seed))
    side = _parts(replace(p, handle="side"))
    assert side["handle"].bounds[1, 0] < 0.0  # entirely on the -x side
    assert side["handle"].bounds[0, 0] < side["body"].bounds[0, 0]  # and standing off the body
    top = _parts(replace(p, handle="top"))
    assert top["handle"].bounds[1, 2] > top["lid"].bounds[1, 2]  # arches over the lid and its knob
