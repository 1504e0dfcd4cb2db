"""Eyeglasses: lenses sit in their rims, the two eyes mirror each other, and temples run back toward +y."""

from __future__ import annotations

import numpy as np

from affnerf.objects.registry import make_object


def _parts(seed: int):
    return {p.name: p for p in make_object("eyeglasses", seed).parts}


def test_lenses_sit_inside_their_rims():
    for seed in range(8):
        asset = make_object("eyeglasses", seed)
        parts = {p.name: p for p in asset.parts}
        for side in ("left", "right"):
            lens, rim = parts[f"lens_{side}"].mesh.bounds, parts[f"rim_{side}"].mesh.bounds
            assert lens[0, 0] > rim[0, 0] and lens[1, 0] < rim[1, 0], (seed, side)  # across, within the rim
            assert lens[1, 2] < rim[1, 2], (seed, side)  # the rim runs over the lens's top
            if asset.params["rims"] == "full":
                assert lens[0, 2] > rim[0, 2], (seed, side)  # and under its bottom
            else:
                assert lens[0, 2] < rim[0, 2], (seed, side)  # a half rim leaves the bottom bare
            assert np.sign(parts[f"lens_{side}"].mesh.centroid[0]) == (1 if side == "right" else -1)


def test_eyes_mirror_each_other_and_temples_go_back():
    parts = _parts(3)
    right = parts["lens_right"].mesh.vertices
    left = parts["lens_left"].mesh.vertices * np.array([-1.0, 1.0, 1.0])
    np.testing.assert_allclose(np.sort(right, axis=0), np.sort(left, axis=0), atol=1e-9)
    front_y = parts["lens_right"].mesh.bounds[1, 1]
    for side in ("left", "right"):
        temple = parts[f"temple_{side}"].mesh
        assert temple.bounds[1, 1] - front_y > 2.0 * np.ptp(parts[f"lens_{side}"].mesh.vertices[:, 0])
        assert temple.vertices[np.argmax(temple.vertices[:, 1]), 2] < temple.vertices[:, 2].max()  # ear hook bends down
