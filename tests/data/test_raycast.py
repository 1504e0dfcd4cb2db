"""Analytic renders: the ray caster gives the exact depth, silhouette, labels and colours expected."""

from __future__ import annotations

import numpy as np
import trimesh

from affnerf.data.cameras import Intrinsics, look_at, pixel_directions
from affnerf.data.raycast import FrameCaster, sample_texture
from affnerf.objects.asset import Material, ObjectAsset, Part, merge_parts
from affnerf.objects.primitives import box, placed, translation

INTR = Intrinsics(80, 60, 60.0, 60.0, 40.0, 30.0)
DOWN = look_at(np.array([0.0, 0.0, 1.0]), np.zeros(3), up=np.array([0.0, 1.0, 0.0]))  # camera at z = 1 looking down


def _render(parts, c2w=DOWN, background=(1.0, 1.0, 1.0)):
    return FrameCaster(merge_parts(ObjectAsset("toy", parts)), background).cast_frame(INTR, c2w)


def test_sphere_depth_and_silhouette_match_the_analytic_sphere():
    radius = 0.2
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=radius)
    frame = _render([Part("ball", "grasp", sphere)])
    d = pixel_directions(INTR).reshape(-1, 3)  # camera frame = world frame here, origin (0, 0, 1)
    o = np.array([0.0, 0.0, 1.0])
    a = (d * d).sum(1)
    b = 2 * d @ o
    c = o @ o - radius**2
    disc = b * b - 4 * a * c
    hit = disc > 0
    t = np.where(hit, (-b - np.sqrt(np.maximum(disc, 0))) / (2 * a), 0.0)
    expected_depth = t.reshape(60, 80)  # z-depth, as the directions have z = -1
    got = frame.depth > 0
    both = got & hit.reshape(60, 80)
    assert np.abs(frame.depth[both] - expected_depth[both]).max() < 2e-3  # tessellation error of the icosphere
    mismatch = got ^ hit.reshape(60, 80)
    # silhouette: only pixels whose centre ray passes within a pixel of the sphere's outline may differ
    closest = np.sqrt(np.maximum(o @ o - (d @ o) ** 2 / a, 0)).reshape(60, 80)
    assert np.all(np.abs(closest[mismatch] - radius) < 1.0 / 60.0)
    assert mismatch.sum() <= 0.05 * hit.sum()


def test_box_depth_is_exact_and_labels_follow_parts():
    top = 0.1
    base = Part("base", "support", placed(box((0.3, 0.2, 2 * top)), translation((0, 0, 0))))
    knob = Part("knob", "pull", placed(box((0.05, 0.05, 0.1)), translation((0.0, 0.0, top + 0.05))))
    frame = _render([base, knob])
    # pixel (u, v) centre ray hits the top face z = top at distance 1 - top, the knob's top at 1 - top - 0.1
    v, u = np.mgrid[0:60, 0:80]
    x = (u + 0.5 - 40) / 60 * (1 - top)
    y = -(v + 0.5 - 30) / 60 * (1 - top)
    on_base = (np.abs(x) < 0.15) & (np.abs(y) < 0.1)
    xk = (u + 0.5 - 40) / 60 * (1 - top - 0.1)
    yk = -(v + 0.5 - 30) / 60 * (1 - top - 0.1)
    on_knob = (np.abs(xk) < 0.025) & (np.abs(yk) < 0.025)
    expected_part = np.where(on_knob, 2, np.where(on_base, 1, 0))
    np.testing.assert_array_equal(frame.part, expected_part)
    np.testing.assert_array_equal(frame.affordance, np.where(on_knob, 6, np.where(on_base, 11, 0)))
    np.testing.assert_allclose(frame.depth[on_knob], 1 - top - 0.1, atol=1e-5)
    np.testing.assert_allclose(frame.depth[on_base & ~on_knob], 1 - top, atol=1e-5)
    assert np.all(frame.depth[expected_part == 0] == 0)


def test_background_is_exact_and_shading_follows_the_camera_light():
    frame = _render(
        [Part("p", "grasp", box((0.2, 0.2, 0.2)), (Material((0.5, 0.5, 0.5)),))], background=(0.0, 1.0, 0.0)
    )
    bg = frame.part == 0
    assert np.all(frame.rgb[bg] == [0, 255, 0])
    # top face, normal +z: light = 0.35 + 0.65 * cos(angle between the normal and the pixel's ray)
    d = pixel_directions(INTR)
    cos = 1.0 / np.linalg.norm(d, axis=2)
    expected = np.round(255 * 0.5 * (0.35 + 0.65 * cos))
    seen = frame.part == 1
    assert np.abs(frame.rgb[seen][:, 0] - expected[seen]).max() <= 1


def test_texture_lookup_is_bilinear_and_wraps():
    image = np.zeros((2, 2, 3), np.uint8)
    image[1, 0] = 255  # bottom-left texel (v = 0 is the image's bottom row)
    got = sample_texture(image, np.array([[0.25, 0.25], [1.25, 0.25], [0.5, 0.5]]))
    np.testing.assert_allclose(got[0], [1, 1, 1])
    np.testing.assert_allclose(got[1], [1, 1, 1])  # wraps around
    np.testing.assert_allclose(got[2], [0.25, 0.25, 0.25])  # the four texels' average
