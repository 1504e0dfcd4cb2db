"""Where rays land: on the object, near its outline, near the edges between its parts."""

from __future__ import annotations

import numpy as np

from affnerf.train.cache import ObjectFrames, part_edge_index
from affnerf.train.pixels import draw_edge_pixels, draw_pixels, input_view_chances


def test_foreground_draws_fall_back_to_uniform_where_no_object_is_seen():
    labels = np.zeros((2, 5, 7), np.uint8)
    labels[1, 2, 3] = 4
    frames = ObjectFrames(
        "toy",
        np.zeros((2, 5, 7, 3), np.uint8),
        labels,
        np.zeros((2, 5, 7), np.float16),
        np.zeros((2, 4, 4, 3), np.uint8),
        np.zeros((2, 4)),
        np.array([0, 0, 1]),
        np.array([2 * 7 + 3], np.int32),
        np.tile(np.eye(4), (2, 1, 1)),
        np.ones(4),
        np.ones(3),
    )
    rng = np.random.default_rng(0)
    u, v = draw_pixels(rng, frames, np.array([0, 1, 1, 1]), np.array([True, True, True, False]))
    assert (u[1], v[1]) == (3, 2) and (u[2], v[2]) == (3, 2)
    assert 0 <= u[0] < 7 and 0 <= v[0] < 5


def test_near_rays_land_within_the_band_around_the_object():
    labels = np.zeros((1, 20, 30), np.uint8)
    labels[0, 8:12, 10:14] = 2  # a 4 x 4 object
    flat = np.flatnonzero(labels[0]).astype(np.int32)
    frames = ObjectFrames(
        "toy", np.zeros((1, 20, 30, 3), np.uint8), labels, np.zeros((1, 20, 30), np.float16),
        np.zeros((1, 4, 4, 3), np.uint8), np.zeros((1, 4)), np.array([0, len(flat)]), flat,
        np.tile(np.eye(4), (1, 1, 1)), np.ones(4), np.ones(3),
    )  # fmt: skip
    n = 4000
    u, v = draw_pixels(np.random.default_rng(1), frames, np.zeros(n, int), np.zeros(n, bool), np.ones(n, bool), 3)
    assert u.min() >= 7 and u.max() <= 16 and v.min() >= 5 and v.max() <= 14  # the object grown by 3 pixels
    outside = labels[0, v, u] == 0
    assert 0.3 < outside.mean() < 0.9  # both sides of the outline


def test_edge_rays_land_on_the_band_between_parts_and_frames_without_edges_keep_their_pixels():
    labels = np.zeros((2, 20, 30), np.uint8)
    labels[:, 5:15, 5:12] = 1  # a handle ...
    labels[0, 5:15, 12:25] = 2  # ... and a blade beside it in frame 0; frame 1 shows the handle alone
    edges = part_edge_index(labels)
    assert edges[0].tolist() == [0, 20, 20]  # columns 11 and 12, rows 5-14; none in frame 1
    n = 3000
    views = np.repeat([0, 1], n // 2)
    u0, v0 = np.full(n, 7), np.full(n, 9)
    u, v = draw_edge_pixels(np.random.default_rng(0), edges, (20, 30), views, np.ones(n, bool), u0, v0, 1)
    first = views == 0
    assert u[first].min() == 10 and u[first].max() == 13 and v[first].min() == 4 and v[first].max() == 15
    assert set(np.unique(u[first]).tolist()) == {10, 11, 12, 13}  # both sides of the edge
    assert (u[~first] == 7).all() and (v[~first] == 9).all()  # no edge in frame 1: the pixel stays
    assert (u0 == 7).all()  # the inputs are not changed


def test_input_view_chances_leave_out_cut_frames_and_keep_the_uniform_choice_where_they_cannot():
    labels = np.zeros((4, 6, 8), np.uint8)
    labels[0, 2:4, 2:5] = 1  # whole
    labels[1, 0:3, 2:5] = 1  # touches the top row
    labels[2, 2:4, 5:8] = 3  # touches the right column
    labels[3, 1:5, 1:7] = 2  # whole
    np.testing.assert_allclose(input_view_chances(labels, 0.0), [0.5, 0.0, 0.0, 0.5])
    np.testing.assert_allclose(input_view_chances(labels, 0.5), [1 / 3, 1 / 6, 1 / 6, 1 / 3])
    assert input_view_chances(labels, 1.0) is None
    assert input_view_chances(labels, 0.0, views=3) is None  # two whole frames cannot give three views
    assert input_view_chances(labels[[1, 2]], 0.0) is None  # every frame cut: nothing to prefer
    assert input_view_chances(labels[[0, 3]], 0.0) is None  # none cut
