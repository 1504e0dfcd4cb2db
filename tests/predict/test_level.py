"""The per-object mesh level (affnerf.predict.level): a diffuse object's level drops to where it renders opaque,
a sharp one keeps the calibrated level."""

import numpy as np
import pytest

from affnerf.predict.level import LEVEL_CANDIDATES, axis_silhouettes, object_level, silhouette_level

R = 41
HALF = 0.25
SPACING = 2 * HALF / (R - 1)


def _radius_grid() -> np.ndarray:
    axis = np.linspace(-HALF, HALF, R)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    return np.sqrt(x**2 + y**2 + z**2)


def diffuse_ball(radius: float = 0.15, peak: float = 40.0) -> np.ndarray:
    """Density that falls linearly from ``peak`` at the centre to 0 at ``radius`` (a blurry object)."""
    return np.clip(peak * (1.0 - _radius_grid() / radius), 0.0, None)


def sharp_ball(radius: float = 0.1, density: float = 400.0) -> np.ndarray:
    """Density ``density`` inside ``radius``, 0 outside (a crisp object)."""
    return np.where(_radius_grid() <= radius, density, 0.0)


def test_projections_are_the_axis_max_and_integral():
    volume = np.random.default_rng(0).random((5, 5, 5))
    peaks, depths = axis_silhouettes(volume, 0.1)
    for axis in range(3):
        np.testing.assert_allclose(peaks[axis], volume.max(axis=axis))
        np.testing.assert_allclose(depths[axis], volume.sum(axis=axis) * 0.1)


def test_a_diffuse_ball_is_meshed_where_it_renders_opaque():
    volume = diffuse_ball()
    level = silhouette_level(volume, SPACING, optical_depth=1.0)
    # rays through the ball are opaque (optical depth > 1) out to a radius r0; its level-L outline has radius
    # 0.15 (1 - L/40); the chosen level must put that outline within two grid cells of r0
    depths = axis_silhouettes(volume, SPACING)[1][2]
    axis = np.linspace(-HALF, HALF, R)
    opaque_radius = np.abs(axis[np.nonzero(depths[:, R // 2] > 1.0)[0]]).max()
    outline_radius = 0.15 * (1.0 - level / 40.0)
    assert abs(outline_radius - opaque_radius) <= 2 * SPACING
    assert object_level(volume, SPACING, 35.0, 1.0) == level < 35.0


def test_a_sharp_object_keeps_the_calibrated_level():
    assert object_level(sharp_ball(), SPACING, 35.0, 3.0) == 35.0
    assert object_level(sharp_ball(), SPACING, 37.5, 3.0) == 37.5


def test_zero_optical_depth_switches_the_rule_off():
    assert object_level(diffuse_ball(), SPACING, 35.0, 0.0) == 35.0


def test_a_field_never_opaque_keeps_the_calibrated_level():
    faint = diffuse_ball(peak=1.0)
    assert silhouette_level(faint, SPACING, optical_depth=3.0) is None
    assert object_level(faint, SPACING, 35.0, 3.0) == 35.0


@pytest.mark.parametrize("depth", [1.0, 2.0, 4.0])
def test_a_more_demanding_optical_depth_never_raises_the_outline(depth):
    volume = diffuse_ball()
    assert silhouette_level(volume, SPACING, depth) >= silhouette_level(volume, SPACING, depth / 2)
    assert silhouette_level(volume, SPACING, depth) in LEVEL_CANDIDATES
