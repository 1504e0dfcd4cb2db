"""The object segmenter network: shapes, padding, save and load, and the shipped weights on a cluttered photo."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import torch

from affnerf.errors import AffnerfError
from affnerf.model import segmenter as segnet

TINY = segnet.SegmenterConfig(base=4, levels=2, input_side=40)


def test_network_input_keeps_the_aspect_and_pads_to_the_stride():
    x, size = segnet.network_input(np.zeros((30, 50, 3), np.uint8), TINY)
    assert size == (40, 24) and tuple(x.shape) == (1, 3, 24, 40)
    x, size = segnet.network_input(np.zeros((50, 27, 3), np.uint8), TINY)
    assert size == (22, 40) and tuple(x.shape) == (1, 3, 40, 24)  # 22 padded to 24, a multiple of 2**2


def test_probability_has_the_photos_size_whatever_its_shape():
    torch.manual_seed(0)
    model = segnet.ObjectSegmenter(TINY).eval()
    for shape in ((30, 50, 3), (51, 17, 3)):
        prob = segnet.object_probability(model, np.random.default_rng(0).integers(0, 255, shape, np.uint8))
        assert prob.shape == shape[:2] and prob.dtype == np.float32 and 0.0 <= prob.min() <= prob.max() <= 1.0


def test_the_mask_keeps_a_faint_thin_part_and_sure_fragments_but_not_unsure_ones():
    prob = np.zeros((20, 80), np.float32)
    prob[5:15, 2:12] = 0.97  # a handle
    prob[9:11, 12:26] = 0.45  # a thin shaft the segmenter is unsure of, joined to it
    prob[8:12, 30:34] = 0.95  # a sure fragment beyond a gap
    prob[0:3, 36:40] = 0.6  # an unsure blob
    prob[8:12, 60:64] = 0.99  # a sure thing far away: another thing
    prob[18:20, 0:20] = 0.45  # faint everywhere, joined to nothing sure
    mask = segnet.probability_mask(prob)
    assert mask[5:15, 2:12].all() and mask[9:11, 12:26].all() and mask[8:12, 30:34].all()
    assert not mask[0:3, 36:40].any() and not mask[18:20].any() and not mask[:, 40:].any()
    assert mask.sum() == 100 + 28 + 16
    inside = np.zeros_like(mask)
    inside[:, :20] = True  # a box: the fragment and the shaft's far end are outside
    boxed = segnet.probability_mask(prob, inside)
    assert boxed.sum() == 100 + 16 and not boxed[:, 20:].any()


def test_the_main_region_is_the_sure_object_not_a_larger_unsure_subject():
    prob = np.zeros((40, 120), np.float32)
    prob[5:35, 5:45] = 0.84  # the photo's own subject, 1200 px the segmenter half believes
    prob[10:30, 80:100] = 0.97  # the object, 400 px it is sure of
    mask = segnet.probability_mask(prob)
    assert mask[10:30, 80:100].all() and not mask[:, :60].any()
    prob[0:40, 0:60] = 0.84  # 2400 px of it: over three times the object's score, it wins again
    assert segnet.probability_mask(prob)[:, :60].all() and not segnet.probability_mask(prob)[:, 60:].any()


class NearTheBrightest(torch.nn.Module):
    """A network that reads the whole image it is given: a pixel is object when it is bright (above 0.5) and within
    0.1 of the brightest pixel's brightness (what a salient model does with context, in one line)."""

    config = replace(TINY, input_side=60)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        grey = x.mean(dim=1, keepdim=True)
        return 60.0 * torch.minimum(grey - grey.amax() + 0.1, grey - 0.5)


def test_tile_windows_are_four_corners_covering_the_image():
    for h, w in ((300, 400), (31, 17)):
        cover = np.zeros((h, w), int)
        for y0, y1, x0, x1 in segnet.tile_windows(h, w, 0.6):
            assert y1 - y0 == round(0.6 * h) and x1 - x0 == round(0.6 * w)
            cover[y0:y1, x0:x1] += 1
        assert cover.min() >= 1 and cover[0, 0] == cover[-1, -1] == 1 and cover[h // 2, w // 2] == 4


def test_a_small_object_beside_a_brighter_subject_is_found_on_a_tile():
    photo = np.full((60, 80, 3), 50, np.uint8)
    photo[2:22, 2:30] = 255  # the photo's own subject, top left
    photo[48:54, 66:74] = 180  # a small object, bottom right: dimmer than the subject
    model = NearTheBrightest()
    whole = segnet.object_probability(model, photo)
    assert whole[50, 70] < 0.1 and whole[10, 10] > 0.9  # the whole photo sees the subject only
    tiles = segnet.tiled_probability(model, photo)
    assert tiles[50, 70] > 0.9  # the bottom-right tile does not hold the subject: the object is its brightest
    both = segnet.photo_probability(model, photo)
    assert both[50, 70] > 0.9 and both[10, 10] > 0.9 and both[35, 40] < 0.1
    assert np.array_equal(both, np.maximum(whole, tiles))
    assert np.array_equal(segnet.photo_probability(model, photo, share=None), whole)


def test_save_and_load_give_the_same_probabilities(tmp_path):
    torch.manual_seed(0)
    model = segnet.ObjectSegmenter(TINY).eval()
    path = tmp_path / "seg.pt"
    segnet.save_segmenter(model, path, {"note": "test"})
    loaded = segnet.load_segmenter(path)
    assert loaded.config == TINY
    photo = np.random.default_rng(1).integers(0, 255, (30, 40, 3), np.uint8)
    assert np.array_equal(segnet.object_probability(model, photo), segnet.object_probability(loaded, photo))
    assert torch.load(path, weights_only=True)["provenance"] == {"note": "test"}


def test_a_file_that_is_not_a_segmenter_is_an_error_naming_it(tmp_path):
    bad = tmp_path / "bad.pt"
    bad.write_text("not weights")
    with pytest.raises(AffnerfError, match="bad.pt: not an affnerf object segmenter"):
        segnet.load_segmenter(bad)


def test_a_trained_segmenter_finds_its_objects_on_a_photo_it_never_saw(train_dataset, trained_segmenter):
    """Renders of the training objects pasted onto scikit-image's coffee photo (never used in training)."""
    import skimage.data

    from affnerf.data.composite import cut_to_box, paste
    from affnerf.data.dataset import Dataset
    from affnerf.predict.segment import mask_iou

    ds = Dataset.open(train_dataset)
    obj = ds.load_object(ds.objects("train")[0])
    photo = np.ascontiguousarray(skimage.data.coffee()[::4, ::4])
    rng = np.random.default_rng(0)
    model = segnet.load_segmenter(trained_segmenter)
    ious = []
    for view in range(4):
        rgb, alpha = paste(rng, photo, cut_to_box(obj.rgb(view), obj.affordance(view) > 0), scale=(0.4, 0.7))
        ious.append(mask_iou(segnet.object_probability(model, rgb) > segnet.SEGMENTER_THRESHOLD, alpha > 0.5))
    assert np.mean(ious) > 0.3, ious


def test_an_ensemble_votes_with_each_member_at_its_own_size(tmp_path):
    torch.manual_seed(0)
    small, large = segnet.ObjectSegmenter(TINY).eval(), segnet.ObjectSegmenter(replace(TINY, input_side=64)).eval()
    photo = np.random.default_rng(2).integers(0, 255, (30, 40, 3), np.uint8)
    ensemble = segnet.SegmenterEnsemble([small, large])
    expected = (segnet.object_probability(small, photo) + segnet.object_probability(large, photo)) / 2
    assert np.allclose(segnet.object_probability(ensemble, photo), expected, atol=1e-6)
    assert not np.allclose(segnet.object_probability(small, photo), segnet.object_probability(large, photo))


def test_combined_segmenters_are_saved_and_read_back_as_one_ensemble(tmp_path):
    torch.manual_seed(0)
    a, b = segnet.ObjectSegmenter(TINY).eval(), segnet.ObjectSegmenter(replace(TINY, input_side=64)).eval()
    segnet.save_segmenter(a, tmp_path / "a.pt")
    segnet.save_segmenter(b, tmp_path / "b.pt")
    segnet.combine_segmenters([tmp_path / "a.pt", tmp_path / "b.pt"], tmp_path / "ab.pt", {"note": "two"})
    both = segnet.combine_segmenters([tmp_path / "ab.pt", tmp_path / "a.pt"], tmp_path / "aba.pt")  # flattened
    read = segnet.read_segmenter(tmp_path / "ab.pt")
    assert isinstance(read, segnet.SegmenterEnsemble) and [m.config for m in read.members] == [a.config, b.config]
    assert len(both.members) == 3 and torch.load(tmp_path / "ab.pt", weights_only=True)["provenance"] == {"note": "two"}
    assert segnet.networks(a) == [a] and [m.config for m in segnet.networks(read)] == [a.config, b.config]
    photo = np.random.default_rng(3).integers(0, 255, (30, 40, 3), np.uint8)
    want = segnet.object_probability(segnet.SegmenterEnsemble([a, b]), photo)
    assert np.array_equal(segnet.object_probability(read, photo), want)


def test_combining_a_file_that_is_not_a_segmenter_is_an_error_naming_it(tmp_path):
    (tmp_path / "bad.pt").write_text("no")
    with pytest.raises(AffnerfError, match="bad.pt: not an affnerf object segmenter"):
        segnet.combine_segmenters([tmp_path / "bad.pt"], tmp_path / "out.pt")
    assert not (tmp_path / "out.pt").exists()
