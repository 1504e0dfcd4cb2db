"""GrabCut from a rectangle or a trimap, and the trimaps that redraw another method's mask."""

from __future__ import annotations

import numpy as np
import pytest
from support import disc_with_a_thin_bar

from affnerf.data.composite import largest_component
from affnerf.predict import grabcut

needs_opencv = pytest.mark.skipif(grabcut.opencv() is None, reason="opencv-python-headless is not installed")


def test_trimap_is_sure_inside_and_far_outside_and_unsure_along_the_edge():
    mask = np.zeros((40, 40), bool)
    mask[5:25, 5:25] = True
    labels = grabcut.trimap(mask)
    assert labels[15, 15] == 1 and labels[0, 39] == 0  # sure object inside, sure background far away
    assert set(np.unique(labels[5, 4:7])) == {2, 3}  # unsure on both sides of the edge


def test_the_probability_trimap_leaves_what_the_map_half_believes_unsure():
    prob = np.full((60, 60), 0.02, np.float32)
    prob[10:40, 10:40] = 0.97
    prob[55, 55] = 0.3  # far outside the mask, half believed
    mask = prob > 0.5
    plain, guided = grabcut.trimap(mask, 0.04), grabcut.probability_trimap(prob, mask, band=0.04, sure_object=None)
    assert plain[55, 55] == 0 and guided[55, 55] == 2  # left for GrabCut to decide
    changed = plain != guided
    assert changed.sum() == 1 and (plain[changed] == 0).all()  # only sure background can become unsure


@needs_opencv
def test_guided_by_the_probabilities_grabcut_recovers_a_thin_part_the_mask_lost():
    rgb, disc, bar = disc_with_a_thin_bar()
    prob = np.where(disc, 0.97, np.where(bar, 0.3, 0.02)).astype(np.float32)  # the bar: seen, but not believed
    mask = prob > 0.5
    plain = grabcut.refine_with_grabcut(rgb, mask)
    guided = grabcut.refine_with_grabcut(rgb, mask, prob)
    far_bar = bar & (np.arange(rgb.shape[1]) < 120)[None, :]  # beyond the plain trimap's unsure band
    assert not plain[far_bar].any()
    assert guided[far_bar].mean() > 0.9 and guided[disc].mean() > 0.98
    assert (guided & ~(disc | bar)).sum() < 0.02 * disc.sum()  # no clutter taken with it


def test_the_probability_trimap_is_sure_of_thin_parts_the_map_is_sure_of_and_of_nothing_else():
    prob = np.full((80, 80), 0.02, np.float32)
    prob[10:50, 10:50] = 0.97  # a fat body: sure only deep inside (the band's erosion)
    prob[60, 5:75] = 0.95  # a thin bar the map is sure of
    prob[70, 5:75] = 0.6  # a thin bar it half believes
    mask = prob > 0.5
    labels = grabcut.probability_trimap(prob, mask, band=0.04)
    assert (labels[60, 5:75] == 1).all() and (labels[70, 5:75] == 3).all()
    assert labels[11, 30] == 3  # the body's edge stays GrabCut's to redraw: it is not thin
    before = grabcut.probability_trimap(prob, mask, band=0.04, sure_object=None)
    changed = labels != before
    assert (before[60, 5:75] == 3).all() and (before[changed] == 3).all() and (prob[changed] >= 0.8).all()
    assert changed[:55].sum() <= 4 * 4  # of the body, at most its corners (a disc does not fit into a corner)


@needs_opencv
def test_grabcut_keeps_a_thin_part_the_map_is_sure_of_even_where_it_has_the_backgrounds_colours():
    rgb, disc, bar = disc_with_a_thin_bar()
    rgb[bar] = np.roll(rgb, 6, 0)[bar]  # the bar painted with the clutter beside it: only the map knows it
    prob = np.where(disc, 0.97, np.where(bar, 0.95, 0.02)).astype(np.float32)
    mask = prob > 0.5
    before = largest_component(grabcut.grabcut_labels(rgb, grabcut.probability_trimap(prob, mask, sure_object=None)))
    now = grabcut.refine_with_grabcut(rgb, mask, prob)
    assert before[bar].mean() < 0.5  # GrabCut's colour models gave it to the background
    assert now[bar].all() and now[disc].mean() > 0.98 and not (now & ~(disc | bar)).any()


@needs_opencv
def test_grabcut_gives_the_same_mask_whatever_opencvs_random_state():
    """GrabCut's colour models start from k-means++ on OpenCV's process-wide generator: without seeding it, a photo's
    mask depended on the GrabCuts run before it (here 3 pixels of this photo differ between two states)."""
    import cv2
    import skimage.data

    photo = np.ascontiguousarray(skimage.data.coffee()[::4, ::4])
    masks = []
    for state in (1, 2, 3):
        cv2.setRNGSeed(state)  # what earlier GrabCuts would have left behind
        masks.append(grabcut.grabcut_mask(photo))
    assert masks[0].any() and all((m == masks[0]).all() for m in masks[1:])


@needs_opencv
def test_grabcut_on_an_image_too_small_for_its_rectangle_finds_nothing_instead_of_failing():
    rgb = (np.random.default_rng(0).random((40, 2, 3)) * 255).astype(np.uint8)
    assert not grabcut.grabcut_mask(rgb).any()
    assert grabcut.grabcut_mask(np.pad(rgb, ((0, 0), (0, 1), (0, 0)))).shape == (40, 3)
