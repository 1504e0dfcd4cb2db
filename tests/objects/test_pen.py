"""Pens: the cap's styles decide whether a pen can be opened and where the cap sits."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from affnerf.objects.asset import Material
from affnerf.objects.categories import pen


def _pen(seed: int, **changes):
    params = replace(pen.sample_params(np.random.default_rng(seed)), **changes)
    return {p.name: p for p in pen.build(params, Material(), Material(), Material(), Material()).parts}


def test_capless_pen_has_no_open_part_but_keeps_its_tip():
    parts = _pen(0, cap="none", clip=True)
    assert "cap" not in parts and {p.affordance for p in parts.values()} == {"grasp", "write"}
    assert parts["clip"].mesh.bounds[0, 0] > parts["barrel"].mesh.bounds[0, 0]  # the clip sits on the barrel


def test_cap_on_the_tip_covers_it_and_a_posted_cap_sits_behind_the_barrel():
    on_tip = _pen(1, cap="on_tip")
    ball = on_tip["tip"].mesh.vertices[np.argmax(on_tip["tip"].mesh.vertices[:, 0])]
    assert on_tip["cap"].mesh.contains([ball])[0]
    posted = _pen(1, cap="posted")
    assert posted["cap"].mesh.bounds[0, 0] < posted["barrel"].mesh.bounds[0, 0]
    assert posted["tip"].mesh.bounds[1, 0] == max(p.mesh.bounds[1, 0] for p in posted.values())  # tip leads at +x
