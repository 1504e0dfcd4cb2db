"""Camera conventions of conventions §1."""

from __future__ import annotations

import numpy as np

from affnerf.data.cameras import (
    CameraSampler,
    Intrinsics,
    look_at,
    pixel_directions,
    project,
    unproject_depth,
    world_rays,
)


def test_pixel_centre_direction_follows_the_conventions():
    intr = Intrinsics(400, 300, 350.0, 340.0, 200.0, 150.0)
    d = pixel_directions(intr)
    u, v = 17, 250
    np.testing.assert_allclose(d[v, u], [(u + 0.5 - 200.0) / 350.0, -(v + 0.5 - 150.0) / 340.0, -1.0])


def test_look_at_is_opengl_camera_to_world():
    eye = np.array([0.3, -0.4, 0.5])
    c2w = look_at(eye, np.zeros(3))
    np.testing.assert_allclose(c2w[:3, 3], eye)
    forward = -c2w[:3, 2]
    np.testing.assert_allclose(forward, -eye / np.linalg.norm(eye))
    assert c2w[2, 1] > 0  # camera +y points up-ish in the world
    np.testing.assert_allclose(c2w[:3, :3] @ c2w[:3, :3].T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(c2w[:3, :3]), 1.0)


def test_sampler_stays_on_the_upper_hemisphere_band():
    poses = CameraSampler().sample(np.random.default_rng(0), 500)
    eyes = poses[:, :3, 3]
    radius = np.linalg.norm(eyes, axis=1)
    elevation = np.degrees(np.arcsin(eyes[:, 2] / radius))
    assert radius.min() >= 0.5 and radius.max() <= 0.9
    assert elevation.min() >= 10 and elevation.max() <= 80
    # every camera looks close to the origin
    to_origin = -eyes / radius[:, None]
    assert np.all(np.einsum("nk,nk->n", -poses[:, :3, 2], to_origin) > np.cos(np.radians(10)))


def test_project_inverts_unproject_and_world_rays():
    intr = Intrinsics.from_fov(40, 30, 1.0)
    c2w = look_at(np.array([0.2, -0.5, 0.4]), np.zeros(3))
    depth = np.random.default_rng(1).uniform(0.3, 1.0, (30, 40))
    points = unproject_depth(depth, intr, c2w).reshape(-1, 3)
    pix, z = project(points, intr, c2w)
    vv, uu = np.mgrid[0:30, 0:40]
    np.testing.assert_allclose(pix, np.stack([uu.ravel() + 0.5, vv.ravel() + 0.5], 1), atol=1e-9)
    np.testing.assert_allclose(z, depth.ravel(), atol=1e-12)
    origins, dirs = world_rays(intr, c2w)
    np.testing.assert_allclose(origins + dirs * depth.reshape(-1, 1), points, atol=1e-12)


def test_scaled_intrinsics_keep_the_field_of_view():
    intr = Intrinsics.from_fov(400, 300, 1.0)
    half = intr.scaled(0.5)
    assert (half.width, half.height) == (200, 150)
    np.testing.assert_allclose(half.camera_angle_x, intr.camera_angle_x)
