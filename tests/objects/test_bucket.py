"""Buckets: the body is a hollow container and the bail stays off it, upright or dropped."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from affnerf.objects.asset import Material
from affnerf.objects.categories import bucket


def _bucket(seed: int, **changes):
    params = replace(bucket.sample_params(np.random.default_rng(seed)), **changes)
    parts = {p.name: p for p in bucket.build(params, Material(), Material(), Material()).parts}
    return params, parts


def test_body_is_hollow_with_a_floor_and_a_wall():
    for seed in range(4):
        p, parts = _bucket(seed)
        body = parts["body"].mesh
        z_mid = 0.5 * p.height
        wall_r = float(bucket._outer_radius(p, np.array([z_mid]))[0]) - 0.5 * p.wall
        points = np.array(
            [
                [0.0, 0.0, 1.5 * p.wall + 0.002],  # just above the inner floor, on the axis
                [0.0, 0.0, 0.75 * p.wall],  # inside the floor
                [0.0, p.aspect * wall_r, z_mid],  # inside the wall (the ears are on the x sides)
                [0.0, 0.0, z_mid],  # the middle of the bucket
            ]
        )
        assert body.contains(points).tolist() == [False, True, True, False], seed
        assert abs(body.bounds[1, 2] - p.height) < 1e-9 and abs(body.bounds[0, 2]) < 1e-9


def test_bail_upright_rises_over_the_rim_and_a_dropped_bail_stays_off_the_body():
    p, parts = _bucket(2, handle_tilt=0.0)
    assert parts["bail"].mesh.bounds[1, 2] > p.height + 0.02
    assert abs(parts["bail"].mesh.centroid[1]) < 1e-6
    for seed in range(6):
        p, parts = _bucket(seed, handle_tilt=1.0)
        v = parts["bail"].mesh.vertices
        pivot = np.array([bucket._pivot_x(p), 0.0, bucket._ear_height(p)])
        far = np.minimum(np.linalg.norm(v - pivot, axis=1), np.linalg.norm(v - pivot * [-1, 1, 1], axis=1)) > 0.03
        assert not parts["body"].mesh.contains(v[far]).any(), seed
        assert parts["bail"].mesh.bounds[1, 2] < p.height + 0.5 * p.arc_height * bucket._pivot_x(p)
