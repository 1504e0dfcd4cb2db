"""Synthetic training photos: cutouts, clutter backgrounds, held-out photographs, pasting."""

from __future__ import annotations

import numpy as np

from affnerf.data import composite


def _cutout() -> composite.Cutout:
    rgb = np.zeros((40, 60, 3), np.uint8)
    mask = np.zeros((40, 60), bool)
    mask[10:30, 5:55] = True
    rgb[mask] = (200, 30, 40)
    return composite.cut_to_box(rgb, mask)


def test_cut_to_box_keeps_only_the_objects_box():
    cut = _cutout()
    assert cut.rgb.shape == (20, 50, 3) and cut.mask.all()
    assert composite.cut_to_box(np.zeros((4, 4, 3), np.uint8), np.zeros((4, 4), bool)) is None


def test_the_benchmarks_backgrounds_are_never_in_the_training_library():
    import skimage.data

    library = composite.photo_library()
    held_out = [np.asarray(getattr(skimage.data, n)())[..., :3] for n in ("astronaut", "coffee", "chelsea", "rocket")]
    assert len(library) >= 10
    shapes = {p.shape for p in library}
    for photo in held_out:  # none of them is in the library (same size and same pixels)
        assert photo.shape not in shapes or not any(
            p.shape == photo.shape and np.array_equal(p, photo) for p in library
        )
    assert len(composite.photo_library(exclude=())) == len(library) + len(composite.HELD_OUT_BACKGROUNDS)


def test_dead_leaves_fill_the_frame_with_many_colours():
    image = composite.dead_leaves(np.random.default_rng(0), (96, 64))
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 50


def test_paste_puts_the_object_where_its_mask_says():
    rng = np.random.default_rng(1)
    background = np.full((72, 96, 3), 20, np.uint8)
    for _ in range(10):
        rgb, alpha = composite.paste(rng, background, _cutout())
        mask = alpha > 0.5
        h, w = np.flatnonzero(mask.any(1)), np.flatnonzero(mask.any(0))
        ratio = (w[-1] - w[0] + 1) / (h[-1] - h[0] + 1)
        assert 2.0 < ratio < 3.0  # the 50 x 20 object keeps its shape
        inner = alpha > 0.99
        assert np.abs(rgb[inner].astype(int) - (200, 30, 40)).max() <= 1  # object pixels are the object's
        assert (rgb[alpha == 0] <= 20).all()  # the background only ever darkens (shadow)
        assert composite.OBJECT_SCALE[0] * 72 - 2 <= max(w[-1] - w[0], h[-1] - h[0]) + 1 <= 0.95 * 96 + 1


def test_training_photo_is_an_image_and_its_mask():
    rgb, mask = composite.training_photo(np.random.default_rng(2), _cutout(), composite.photo_library(), (64, 48))
    assert rgb.shape == (48, 64, 3) and mask.shape == (48, 64) and 0.01 < mask.mean() < 0.9


def test_a_fragment_is_a_smaller_piece_with_its_channels_shuffled():
    cut = _cutout()
    rng = np.random.default_rng(3)
    pieces = [composite.fragment(rng, cut) for _ in range(20)]
    for piece in pieces:
        assert piece.mask.shape[0] <= 0.7 * 20 + 1 and piece.mask.shape[1] <= 0.7 * 50 + 1
        assert sorted(piece.rgb[piece.mask][0].tolist()) == [30, 40, 200]  # the same values, any channel order
    assert len({tuple(p.rgb[p.mask][0]) for p in pieces}) > 1


def test_distractor_fragments_are_in_the_photo_but_not_in_its_mask():
    rng = np.random.default_rng(4)
    target = composite.cut_to_box(np.full((30, 30, 3), 250, np.uint8), np.ones((30, 30), bool))
    colours = {(200, 30, 40), (200, 40, 30), (30, 200, 40), (30, 40, 200), (40, 200, 30), (40, 30, 200)}
    with_pieces = 0
    for _ in range(10):
        rgb, mask = composite.training_photo(rng, target, [], (64, 48), [_cutout()])
        assert (rgb[mask] >= 125).all()  # the mask is the white target (edge pixels half blended)
        outside = {tuple(int(c) for c in px) for px in rgb[~mask]}
        with_pieces += bool(outside & colours)  # a distractor's exact colours, outside the mask
    assert with_pieces >= 3


def test_panorama_views_are_overlapping_pieces_of_the_band_round_the_horizon():
    panorama = np.zeros((8, 24, 3), np.uint8)
    panorama[..., 0] = np.arange(24)  # the column index, to see where each view comes from
    panorama[:2, :, 1] = panorama[-2:, :, 1] = 255  # the poles, which no view may show
    views = composite.panorama_views(panorama)
    assert [v.shape for v in views] == [(4, 8, 3)] * 4 and not any(v[..., 1].any() for v in views)
    assert [v[0, :, 0].tolist() for v in views][::3] == [list(range(8)), [18, 19, 20, 21, 22, 23, 0, 1]]  # wraps


def test_the_library_holds_the_real_scenes_the_viewer_ships():
    scenes = composite.scene_photos()
    assert len(scenes) >= 40 and all(s.dtype == np.uint8 and s.shape[2] == 3 for s in scenes)
    assert len(composite.photo_library()) == len(composite.photo_library(scenes=False)) + len(scenes)


def test_a_subject_lies_behind_the_object_and_is_not_in_its_mask():
    rng = np.random.default_rng(5)
    target = composite.cut_to_box(np.full((30, 30, 3), 250, np.uint8), np.ones((30, 30), bool))
    with_subject = 0
    for _ in range(20):
        rgb, mask = composite.training_photo(rng, target, [], (64, 48), subjects=[_cutout()])
        assert (rgb[mask] >= 125).all()
        with_subject += bool((np.abs(rgb[~mask].astype(int) - (200, 30, 40)).max(-1) <= 1).any())
    assert 4 <= with_subject <= 16  # about half of the photos have one


def test_largest_component_keeps_the_biggest_region():
    mask = np.zeros((6, 10), bool)
    mask[0, 0] = True
    mask[2:5, 3:8] = True
    assert composite.largest_component(mask).sum() == 15 and not composite.largest_component(mask)[0, 0]
    assert not composite.largest_component(np.zeros((3, 3), bool)).any()
