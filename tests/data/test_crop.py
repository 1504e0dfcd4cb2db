"""Crops and what is resampled through them."""

from __future__ import annotations

import numpy as np

from affnerf.data.crop import crop_intrinsics, resample_to_crop, touches_border


def test_a_crop_at_the_windows_own_resolution_reads_the_window_pixel_for_pixel():
    image = np.random.default_rng(0).random((8, 10)).astype(np.float32)
    k = np.array([9.0, 9.0, 5.0, 4.0])
    window = (2, 1, 5)  # left, top, side
    crop_k = crop_intrinsics(*k, window, 5)
    np.testing.assert_array_equal(resample_to_crop(image, k, crop_k, 5), image[1:6, 2:7])


def test_a_smaller_crop_takes_the_nearest_pixel_and_keeps_channels():
    image = np.arange(8 * 8 * 2, dtype=np.float64).reshape(8, 8, 2)
    k = np.array([8.0, 8.0, 4.0, 4.0])
    crop_k = crop_intrinsics(*k, (0, 0, 8), 2)  # each crop pixel covers 4 x 4 image pixels: centres at 2.0, 6.0
    out = resample_to_crop(image, k, crop_k, 2)
    assert out.shape == (2, 2, 2)
    np.testing.assert_array_equal(out[..., 0], image[[2, 6]][:, [2, 6], 0])


def test_crop_pixels_outside_the_image_are_zero():
    image = np.ones((6, 6), np.float16)
    k = np.array([6.0, 6.0, 3.0, 3.0])
    crop_k = crop_intrinsics(*k, (-2, 0, 4), 4)  # the window's two left columns lie off the image
    out = resample_to_crop(image, k, crop_k, 4)
    assert out.dtype == np.float16
    np.testing.assert_array_equal(out[:, :2], 0)
    np.testing.assert_array_equal(out[:, 2:], 1)


def test_an_object_touching_any_side_of_the_frame_is_cut():
    masks = np.zeros((6, 5, 7), bool)
    masks[0, 2, 3] = True  # inside
    masks[1, 0, 3] = masks[2, 4, 3] = masks[3, 2, 0] = masks[4, 2, 6] = True  # top, bottom, left, right
    assert touches_border(masks).tolist() == [False, True, True, True, True, False]
    assert touches_border(masks[1]) and not touches_border(masks[0])


def test_the_checkerboard_marks_exactly_the_crop_pixels_outside_the_image():
    from affnerf.data.crop import crop_object, crop_window, mark_outside, outside_image

    rgb = np.full((30, 40, 3), 90, np.uint8)
    mask = np.zeros((30, 40), bool)
    mask[10:30, 0:12] = True  # runs off the bottom and the left of the frame
    window = crop_window(mask)
    outside = outside_image(window, mask.shape, 16)
    mid = outside.shape[0] // 2
    assert window[0] < 0 and outside[:, 0].all() and not outside[mid, -1]  # the left column out, the right in
    assert outside[-1].all() and not outside[mid, mid] and not outside[0, mid]  # the bottom row out, the top in
    crop = crop_object(rgb, mask, 16, (1.0, 1.0, 1.0))
    marked = mark_outside(crop, outside, square=2)
    np.testing.assert_array_equal(marked[~outside], crop[~outside])  # inside the image: untouched
    values = set(np.unique(marked[outside]).tolist())
    assert values == {0, 255}  # outside: black and white squares, never the background alone
    assert not outside_image(crop_window(np.pad(np.ones((4, 4), bool), 10)), (24, 24), 16).any()  # a whole object
