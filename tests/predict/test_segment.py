"""Separating the object of a cluttered photo: auto, salient, GrabCut, uniform, none, and the fallbacks."""

from __future__ import annotations

import logging
import sys

import numpy as np
import pytest
from scipy import ndimage
from support import disc_with_a_thin_bar

from affnerf.errors import AffnerfError
from affnerf.predict import grabcut, salient, segment


def _composite(h=240, w=320, seed=0):
    """A red shape (a disc with a bar) on a textured background of blurred noise and stripes, and its mask."""
    rng = np.random.default_rng(seed)
    noise = ndimage.gaussian_filter(rng.normal(size=(h, w, 3)), (3, 3, 0))
    stripes = np.sin(np.arange(w)[None, :, None] / 5.0 + np.arange(h)[:, None, None] / 9.0)
    bg = 120 + 60 * noise / noise.std() + 25 * stripes * np.array([1.0, 0.6, 0.3])
    yy, xx = np.mgrid[:h, :w]
    obj = ((yy - 120) / 70.0) ** 2 + ((xx - 170) / 55.0) ** 2 <= 1.0
    obj |= (abs(yy - 120) < 12) & (xx > 60) & (xx < 170)
    rgb = np.where(obj[..., None], np.array([210, 40, 30]), bg)
    return np.clip(rgb, 0, 255).astype(np.uint8), obj


def _has_extra() -> bool:
    try:
        salient.load_salient_model()
    except AffnerfError:
        return False
    return grabcut.opencv() is not None


needs_extra = pytest.mark.skipif(
    not _has_extra(), reason="the optional extra affnerf[segment] (onnxruntime, U2-Net-p weights, OpenCV) is not "
    "installed: make install installs it"
)  # fmt: skip
needs_opencv = pytest.mark.skipif(grabcut.opencv() is None, reason="opencv-python-headless is not installed")


@pytest.fixture
def no_salient_model(monkeypatch):
    """onnxruntime made unimportable and the loaded-model cache emptied: the extra looks uninstalled."""
    monkeypatch.setitem(sys.modules, "onnxruntime", None)
    monkeypatch.setattr(salient, "_LOADED", {})


@needs_extra
def test_auto_separates_a_shape_on_a_textured_background_with_the_salient_model():
    rgb, truth = _composite()
    seg = segment.segment(rgb, "auto", segmenter=segment.NO_SEGMENTER)  # the object segmenter left out
    assert seg.source == "salient" and seg.note is None
    assert segment.mask_iou(seg.mask, truth) > 0.8
    assert seg.compared_with == "grabcut" and seg.agreement > 0.8  # two methods ran: their agreement is recorded


@needs_opencv
def test_grabcut_separates_the_same_composite():
    rgb, truth = _composite()
    seg = segment.segment(rgb, "grabcut")
    assert seg.source == "grabcut" and segment.mask_iou(seg.mask, truth) > 0.8


def test_uniform_and_none():
    rgb = np.full((60, 80, 3), 250, np.uint8)
    rgb[20:40, 30:50] = (10, 120, 200)
    for method in ("uniform", "auto"):  # a clean backdrop: auto takes the uniform background, no model runs
        seg = segment.segment(rgb, method)
        assert seg.source == "uniform background" and seg.mask.sum() == 400 and seg.mask[20:40, 30:50].all()
    whole = segment.segment(_composite()[0], "none")
    assert whole.source == "whole image" and whole.mask.all()


def test_an_unknown_method_is_an_error():
    with pytest.raises(AffnerfError, match="unknown separation method 'magic': choose one of auto, segmenter, salient"):
        segment.segment(np.zeros((8, 8, 3), np.uint8), "magic")


@needs_opencv
def test_auto_without_the_model_falls_back_to_grabcut_with_one_warning(no_salient_model, caplog):
    rgb, truth = _composite()
    with caplog.at_level(logging.WARNING, logger="affnerf"):
        seg = segment.segment(rgb, "auto", "photo.jpg", segment.NO_SEGMENTER)
    assert seg.source == "grabcut" and segment.mask_iou(seg.mask, truth) > 0.8
    (record,) = caplog.records
    message = record.getMessage()
    assert message.startswith("photo.jpg: the salient-object model needs onnxruntime") and "\n" not in message
    assert "pip install 'affnerf[segment]'" in message and "separated with GrabCut instead" in message
    assert seg.note in message


def test_auto_without_model_or_opencv_falls_back_to_the_border_colour(no_salient_model, monkeypatch, caplog):
    monkeypatch.setitem(sys.modules, "cv2", None)
    with caplog.at_level(logging.WARNING, logger="affnerf"):
        seg = segment.segment(_composite()[0], "auto", "photo.jpg", segment.NO_SEGMENTER)
    assert seg.source == "uniform background" and len(caplog.records) == 1
    assert "the image border's colour" in caplog.records[0].getMessage()


def test_salient_without_the_model_is_an_error_naming_the_extra(no_salient_model):
    with pytest.raises(
        AffnerfError, match=r"needs onnxruntime, which is not installed: pip install 'affnerf\[segment\]'"
    ):
        segment.segment(_composite()[0], "salient")


def test_largest_component_keeps_the_biggest_region():
    mask = np.zeros((40, 40), bool)
    mask[5:25, 5:25] = mask[30:33, 30:33] = True
    big = segment.largest_component(mask)
    assert big.sum() == 400 and not big[30:33, 30:33].any()


class _WrongModel:
    """A stand-in salient model that finds a blob in the top-left corner, not the object."""

    def saliency(self, rgb):
        sal = np.zeros(rgb.shape[:2], np.float32)
        sal[10:50, 10:50] = 1.0
        return sal


@needs_opencv
def test_when_the_salient_model_and_grabcut_disagree_auto_takes_grabcut_and_records_it():
    rgb, truth = _composite()
    kept = segment.salient_segmentation(rgb, model=_WrongModel())
    assert kept.source == "salient" and kept.agreement < segment.MIN_AGREEMENT and kept.compared_with == "grabcut"
    swapped = segment.salient_segmentation(rgb, model=_WrongModel(), use_grabcut_on_disagreement=True)
    assert swapped.source == "grabcut" and swapped.compared_with == "salient" and swapped.agreement == kept.agreement
    assert segment.mask_iou(swapped.mask, truth) > 0.8


def _training_object_on_coffee(dataset, seed: int = 0):
    """A render of the dataset's first training object pasted onto scikit-image's coffee photo, and its mask."""
    import skimage.data

    from affnerf.data.composite import cut_to_box, paste
    from affnerf.data.dataset import Dataset

    ds = Dataset.open(dataset)
    obj = ds.load_object(ds.objects("train")[0])
    photo = np.ascontiguousarray(skimage.data.coffee()[::4, ::4])
    rgb, alpha = paste(np.random.default_rng(seed), photo, cut_to_box(obj.rgb(0), obj.affordance(0) > 0), (0.5, 0.6))
    return rgb, alpha > 0.5


def test_the_segmenter_method_uses_the_given_file_and_records_its_confidence(train_dataset, trained_segmenter):
    rgb, truth = _training_object_on_coffee(train_dataset)
    seg = segment.segment(rgb, "segmenter", segmenter=trained_segmenter)
    assert seg.source == "segmenter" and seg.agreement is None and 0.5 < seg.confidence <= 1.0
    assert segment.mask_iou(seg.mask, truth) > 0.3
    auto = segment.segment(rgb, "auto", segmenter=trained_segmenter)  # a given segmenter replaces the salient step
    assert auto.source == "segmenter" and np.array_equal(auto.mask, seg.mask)


@pytest.fixture(scope="module")
def rendered_objects(tmp_path_factory):
    """A bottle and a teapot (new draws, not the shipped segmenter's training objects), one 200x150 view."""
    from affnerf.data.generate import GenerateConfig, generate_dataset

    root = tmp_path_factory.mktemp("photo") / "ds"
    config = GenerateConfig(out=root, categories="bottle,teapot", objects_per_category=1, views=1, width=200,
                            height=150, seed=3)  # fmt: skip
    generate_dataset(config, progress=False)
    return root


def test_auto_finds_a_procedural_object_on_a_photo_with_the_shipped_segmenter_and_no_extra(
    rendered_objects, no_salient_model, caplog
):
    """The shipped segmenter is pure PyTorch: with neither onnxruntime nor a --segmenter file, auto uses it, and it
    finds rendered objects on a photograph it never saw in training (scikit-image's cat)."""
    import skimage.data

    from affnerf.data.composite import cut_to_box, paste
    from affnerf.data.dataset import Dataset

    assert segment.resolve_segmenter(None) is not None  # it ships with the package
    ds, photo = Dataset.open(rendered_objects), np.ascontiguousarray(skimage.data.chelsea()[::2, ::2])
    hits = []
    with caplog.at_level(logging.WARNING, logger="affnerf"):
        for k, entry in enumerate(ds.objects()):
            obj = ds.load_object(entry)
            rgb, alpha = paste(np.random.default_rng(k), photo, cut_to_box(obj.rgb(0), obj.affordance(0) > 0))
            seg = segment.segment(rgb, "auto", "photo.jpg")
            assert seg.source == "segmenter" and 0.0 < seg.confidence <= 1.0
            hits.append(segment.mask_iou(seg.mask, alpha > 0.5))
    assert np.mean(hits) > 0.8 and min(hits) > 0.5 and not caplog.records, hits  # no fallback warning
    assert segment.resolve_segmenter(segment.NO_SEGMENTER) is None
    assert segment.resolve_segmenter(segment.SHIPPED_SEGMENTER) == segment.resolve_segmenter(None)  # the CLI default


def test_the_segmenter_method_with_none_installed_is_an_error_saying_how_to_train_one(monkeypatch):
    from affnerf.predict import shipped

    monkeypatch.setattr(shipped, "shipped_segmenter", lambda: None)
    with pytest.raises(AffnerfError, match="needs a segmenter file .none is installed.: train one on your objects"):
        segment.segment(_composite()[0], "segmenter")
    with pytest.raises(AffnerfError, match="needs a segmenter file"):
        segment.segment(_composite()[0], "segmenter", segmenter=segment.NO_SEGMENTER)


def _two_objects():
    """The composite with a second red disc left of the object: a box around the object must leave it out."""
    rgb, truth = _composite()
    yy, xx = np.mgrid[: rgb.shape[0], : rgb.shape[1]]
    distractor = ((yy - 40) / 25.0) ** 2 + ((xx - 40) / 25.0) ** 2 <= 1.0
    rgb[distractor] = (210, 40, 30)
    return rgb, truth & ~distractor


@needs_opencv
def test_a_box_confines_auto_to_grabcut_from_the_rectangle():
    rgb, truth = _two_objects()
    seg = segment.segment(rgb, "auto", box=(50, 40, 235, 200), segmenter=segment.NO_SEGMENTER)
    assert seg.source == "grabcut" and seg.box == (50, 40, 235, 200)
    assert segment.mask_iou(seg.mask, truth) > 0.8
    assert not seg.mask[:40].any() and not seg.mask[:, :50].any()  # nothing outside the box, the distractor left


def test_in_a_box_auto_takes_the_segmenters_mask_only_when_it_is_sure(monkeypatch):
    rgb, truth = _two_objects()
    box = (50, 40, 235, 200)
    seg = segment.segment(rgb, "auto", box=box)  # the shipped segmenter, seeing the whole photo
    assert seg.source == "segmenter" and seg.confidence >= segment.BOX_SEGMENTER_CONFIDENCE and seg.box == box
    assert segment.mask_iou(seg.mask, truth) > 0.8 and not seg.mask[:40].any() and not seg.mask[:, :50].any()
    monkeypatch.setattr(segment, "BOX_SEGMENTER_CONFIDENCE", 1.01)  # never sure enough: GrabCut in the box
    assert segment.segment(rgb, "auto", box=box).source == "grabcut"


def test_a_box_runs_any_method_inside_it_and_is_clipped_to_the_image():
    rgb = np.full((60, 80, 3), 250, np.uint8)
    rgb[20:40, 30:50] = (10, 120, 200)
    rgb[5:10, 5:10] = (10, 120, 200)  # a second object outside the box
    seg = segment.segment(rgb, "uniform", box=(20, 15, 200, 200))
    assert seg.source == "uniform background" and seg.box == (20, 15, 80, 60)
    assert seg.mask.sum() == 400 and seg.mask[20:40, 30:50].all()
    whole = segment.segment(rgb, "none", box=(30, 20, 50, 40))  # none: the whole box is the object
    assert whole.mask.sum() == 400 and whole.mask[20:40, 30:50].all()


@pytest.mark.parametrize("box", [(100, 0, 120, 10), (10, 10, 10, 30), (-20, -20, 0, 0)])
def test_a_box_without_pixels_of_the_image_is_an_error_naming_the_image_and_the_bounds(box):
    with pytest.raises(AffnerfError, match=r"photo.png: --box .* holds no pixel of the 80x60 image: .*X1 <= 80"):
        segment.segment(np.zeros((60, 80, 3), np.uint8), "auto", "photo.png", box=box)


@pytest.mark.parametrize("box", [(10, 10, 12, 50), (10, 10, 40, 17), (395, 10, 450, 60)])
def test_a_box_too_small_to_hold_an_object_is_an_error_naming_the_image_and_its_size(box):
    rgb = (np.random.default_rng(0).random((60, 400, 3)) * 255).astype(np.uint8)  # cluttered: auto takes GrabCut
    with pytest.raises(AffnerfError, match=r"photo.png: --box .* is \d+x\d+ pixels inside the image, too small"):
        segment.segment(rgb, "auto", "photo.png", box=box)


@needs_opencv
def test_a_tight_box_keeps_the_whole_object_and_a_box_of_the_whole_image_still_separates():
    rgb, truth = _two_objects()
    rows, cols = np.flatnonzero(truth.any(1)), np.flatnonzero(truth.any(0))
    tight = (int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1)  # a detector's box, no margin
    seg = segment.segment(rgb, "auto", box=tight)
    assert segment.mask_iou(seg.mask, truth) > 0.8 and seg.mask.sum() > 0.9 * truth.sum()
    whole_image = (0, 0, 320, 240)
    for segmenter in (None, segment.NO_SEGMENTER):  # the shipped segmenter's mask, or GrabCut from the whole image
        whole = segment.segment(_composite()[0], "auto", box=whole_image, segmenter=segmenter)
        assert whole.source == ("grabcut" if segmenter else "segmenter")
        assert segment.mask_iou(whole.mask, _composite()[1]) > 0.8


def test_the_predict_help_states_the_box_rules_confidence():
    from affnerf.predict.outputs import PredictConfig

    stated = f"at least {round(100 * segment.BOX_SEGMENTER_CONFIDENCE)} %"
    doc = " ".join(PredictConfig.__doc__.split())
    assert stated in doc, "PredictConfig.box's doc must state the box rule's threshold"


@needs_opencv
def test_the_segmenters_mask_is_redrawn_from_its_probabilities_and_kept_inside_a_box(monkeypatch):
    rgb, disc, bar = disc_with_a_thin_bar()
    prob = np.where(disc, 0.97, np.where(bar, 0.3, 0.02)).astype(np.float32)  # the bar: seen, not believed
    monkeypatch.setattr(segment, "photo_probability", lambda model, image: prob)
    far_bar = bar & (np.arange(rgb.shape[1]) < 120)[None, :]  # the bar's part outside the disc
    seg = segment.segmenter_segmentation(rgb, model=None)
    assert seg.mask[far_bar].mean() > 0.9 and seg.confidence == pytest.approx(0.97)  # the network's own confidence
    boxed = segment.segmenter_segmentation(rgb, model=None, box=(100, 0, 320, 240))
    assert not boxed.mask[:, :100].any() and boxed.mask[bar & (np.arange(320) >= 100)].mean() > 0.9
    unsure = segment.segmenter_segmentation(rgb, model=None, redraw_from=0.99)  # a caller that drops it: no GrabCut
    assert not unsure.mask[far_bar].any() and unsure.confidence == seg.confidence
    monkeypatch.setattr(segment, "REFINE_SEGMENTER", False)
    assert not segment.segmenter_segmentation(rgb, model=None).mask[far_bar].any()
