"""Scissors: opening the halves about the pivot moves the blade tips and the finger rings apart."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from affnerf.objects.asset import Material
from affnerf.objects.categories import scissors


def _tip_gap(parts) -> float:
    """Distance between the two blades' points farthest from the pivot (the origin)."""
    tips = []
    for name in ("blade_upper", "blade_lower"):
        v = parts[name].mesh.vertices
        tips.append(v[np.argmax(np.linalg.norm(v[:, :2], axis=1))])
    return float(np.linalg.norm(tips[0][:2] - tips[1][:2]))


def _scissors(seed: int, angle: float):
    params = replace(scissors.sample_params(np.random.default_rng(seed)), opening_angle=angle)
    return {p.name: p for p in scissors.build(params, Material(), Material()).parts}


def test_opening_moves_blade_tips_and_rings_apart():
    for seed in range(4):
        closed, half_open, open_ = (_scissors(seed, a) for a in (0.0, 0.25, 0.5))
        assert _tip_gap(closed) < 0.01 * np.ptp(closed["blade_upper"].mesh.vertices[:, 0]) + 1e-3
        assert _tip_gap(closed) < _tip_gap(half_open) < _tip_gap(open_)
        ring_gap = [
            np.linalg.norm(s["handle_upper"].mesh.centroid[:2] - s["handle_lower"].mesh.centroid[:2])
            for s in (closed, open_)
        ]
        assert ring_gap[1] > ring_gap[0]


def test_blades_point_along_x_and_lie_flat():
    parts = _scissors(5, 0.3)
    blade = parts["blade_upper"].mesh
    assert blade.bounds[1, 0] > 0.04 and blade.bounds[0, 0] > -0.03  # the blade runs from the pivot toward +x
    assert parts["handle_upper"].mesh.bounds[0, 0] < -0.03  # the handles toward -x
    extent = np.ptp(np.concatenate([p.mesh.vertices for p in parts.values()]), axis=0)
    assert extent[2] < 0.2 * extent[1] < extent[0]  # thin in z
