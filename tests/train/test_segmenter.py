"""Training the object segmenter: pool, augmentation, loss, and a short run that learns."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from support import SEGMENT_EXTRA_MISSING, salient_weights

from affnerf.data.dataset import Dataset
from affnerf.errors import AffnerfError
from affnerf.model.segmenter import SegmenterConfig, build_segmenter, load_segmenter, object_probability
from affnerf.train import segmenter


def test_loss_is_low_for_the_right_mask_and_high_for_the_wrong_one():
    mask = torch.zeros(2, 1, 16, 16)
    mask[:, :, 4:12, 4:12] = 1.0
    right = segmenter.photo_losses((mask - 0.5) * 20, mask)
    wrong = segmenter.photo_losses((0.5 - mask) * 20, mask)
    assert (right < 0.05).all() and (wrong > 5.0).all()


def test_augment_flips_image_and_mask_together():
    g = torch.Generator().manual_seed(0)
    images = torch.zeros(8, 3, 8, 8, dtype=torch.uint8)
    masks = torch.zeros(8, 1, 8, 8, dtype=torch.bool)
    images[:, :, :, :2], masks[:, :, :, :2] = 255, True
    x, m = segmenter.augment_batch(images, masks, 0.0, g)
    for k in range(8):
        assert torch.equal((x[k, 0] > 0.5), m[k, 0].bool())
    assert 0 < int(m[:, 0, 0, -1].sum()) < 8  # some were flipped, some not


def test_a_short_run_learns_the_masks(train_dataset, trained_segmenter):
    record = torch.load(trained_segmenter, weights_only=True)["provenance"]
    assert record["steps_done"] == 200 and record["curve"][-1]["step"] == 200
    rng = np.random.default_rng(5)
    ds = Dataset.open(train_dataset)
    # new photos of the training objects on new clutter (the tiny dataset has one object per category to learn)
    val = segmenter.make_pool(segmenter.load_cutouts(ds, "train", 8, rng), [], 16, (48, 36), rng)
    untrained = segmenter.mean_mask_iou(build_segmenter(SegmenterConfig(base=8, levels=2, input_side=48)), *val)
    trained = segmenter.mean_mask_iou(load_segmenter(trained_segmenter), *val)
    assert trained > max(0.4, untrained + 0.2), (untrained, trained)
    photo = val[0][0].permute(1, 2, 0).numpy()
    assert object_probability(load_segmenter(trained_segmenter), photo).shape == photo.shape[:2]


def test_training_can_start_from_a_segmenter_file(train_dataset, trained_segmenter, tmp_path):
    cfg = segmenter.SegmenterTrainConfig(
        data=train_dataset, out=tmp_path / "more.pt", steps=1, batch=2, pool=4, val_photos=2, init=trained_segmenter
    )
    segmenter.train_segmenter(cfg)
    assert load_segmenter(cfg.out).config == SegmenterConfig(base=8, levels=2, input_side=48)  # the file's shape


def test_the_learning_rate_warms_up_then_decays():
    rates = [segmenter.learning_rate(1e-3, s, 400) for s in range(400)]
    assert rates[0] == pytest.approx(5e-5) and max(rates) == pytest.approx(1e-3) == rates[19]
    assert all(a >= b for a, b in zip(rates[19:], rates[20:], strict=False)) and rates[-1] == pytest.approx(5e-5, 0.01)


def test_training_can_start_from_the_salient_models_weights(train_dataset, tmp_path):
    if salient_weights("onnx") is None:
        pytest.skip(SEGMENT_EXTRA_MISSING)
    cfg = segmenter.SegmenterTrainConfig(
        data=train_dataset, out=tmp_path / "u2.pt", steps=2, batch=2, pool=4, val_photos=2, init_salient=True,
        precision="bf16", network=SegmenterConfig(input_side=64),
    )  # fmt: skip
    start = segmenter.initial_segmenter(cfg).eval()
    photo = np.random.default_rng(0).integers(0, 255, (48, 64, 3), np.uint8)
    record = segmenter.train_segmenter(cfg)
    trained = load_segmenter(cfg.out)
    assert record["steps_done"] == 2 and trained.config == SegmenterConfig(kind="u2netp", input_side=64)
    assert not np.array_equal(object_probability(start, photo), object_probability(trained, photo))  # it learnt


def test_subjects_are_the_salient_things_cut_out_of_the_photos():
    if salient_weights("onnx") is None:
        pytest.skip(SEGMENT_EXTRA_MISSING)
    photo = np.full((240, 320, 3), 235, np.uint8)
    yy, xx = np.mgrid[:240, :320]
    photo[(yy - 120) ** 2 + (xx - 160) ** 2 < 70**2] = (200, 40, 30)  # a red disk on a plain card
    subjects = segmenter.subject_cutouts([photo], 3, np.random.default_rng(0))
    assert 1 <= len(subjects) <= 3
    for cut in subjects:  # each is the disk (or the part of it in a zoomed crop), not the card
        assert cut.mask.mean() > 0.5 and (cut.rgb[cut.mask][:, 0] > cut.rgb[cut.mask][:, 1] + 80).mean() > 0.9


def test_each_photos_loss_is_its_own_cross_entropy_and_dice():
    g = torch.Generator().manual_seed(0)
    logits, masks = torch.randn(4, 1, 8, 8, generator=g), (torch.rand(4, 1, 8, 8, generator=g) > 0.5).float()
    per = segmenter.photo_losses(logits, masks)
    assert per.shape == (4,)
    assert per[2] == pytest.approx(float(segmenter.photo_losses(logits[2:3], masks[2:3])[0]), rel=1e-6)
    bce = torch.nn.functional.binary_cross_entropy_with_logits(logits, masks)  # the whole batch's pixels
    assert float(segmenter.pixel_bce(logits, masks).mean()) == pytest.approx(float(bce), rel=1e-6)


def test_hard_draws_follow_the_last_losses_and_no_hard_share_draws_uniformly():
    last = torch.full((10,), float("nan"))
    uniform = segmenter.draw_batch(last, 6, 0.0, torch.Generator().manual_seed(4))
    assert torch.equal(uniform, torch.randint(0, 10, (6,), generator=torch.Generator().manual_seed(4)))
    # nothing drawn yet: every draw is uniform, whatever the share
    assert torch.equal(segmenter.draw_batch(last, 6, 0.5, torch.Generator().manual_seed(4)), uniform)
    last[:] = 0.0
    last[7] = 5.0
    picks = segmenter.draw_batch(last, 200, 0.5, torch.Generator().manual_seed(1))
    assert (picks[100:] == 7).all() and (picks[:100] != 7).sum() > 70  # the hard half on the one hard photo
    last[8] = float("nan")  # an undrawn photo counts as the mean of the drawn ones (0.5 here)
    hard = segmenter.draw_batch(last, 4000, 1.0, torch.Generator().manual_seed(2))
    assert 0.05 < float((hard == 8).float().mean()) < 0.13  # 0.5 / 5.5 of the weight


def test_a_hard_share_outside_zero_to_one_is_refused_before_anything_is_written(train_dataset, tmp_path):
    cfg = segmenter.SegmenterTrainConfig(data=train_dataset, out=tmp_path / "s.pt", steps=1, pool=4, hard_share=1.5)
    with pytest.raises(AffnerfError, match="hard-share"):
        segmenter.train_segmenter(cfg)
    assert not cfg.out.exists()


@pytest.mark.parametrize("option", [{"hard_share": 0.5}, {"thin_weight": 4.0}])
def test_a_further_stage_with_hard_photos_or_thin_parts_weighted_trains(
    train_dataset, trained_segmenter, tmp_path, option
):
    cfg = segmenter.SegmenterTrainConfig(
        data=train_dataset, out=tmp_path / "more.pt", steps=3, batch=4, pool=6, val_photos=2, init=trained_segmenter,
        **option,
    )  # fmt: skip
    assert segmenter.train_segmenter(cfg)["steps_done"] == 3 and cfg.out.exists()


def test_training_from_an_ensemble_is_refused_naming_the_file(train_dataset, trained_segmenter, tmp_path):
    from affnerf.model.segmenter import combine_segmenters

    combine_segmenters([trained_segmenter, trained_segmenter], tmp_path / "two.pt")
    cfg = segmenter.SegmenterTrainConfig(
        data=train_dataset, out=tmp_path / "more.pt", steps=1, batch=2, pool=4, val_photos=2, init=tmp_path / "two.pt"
    )
    with pytest.raises(AffnerfError, match="two.pt: an ensemble of 2 segmenters"):
        segmenter.train_segmenter(cfg)
    assert not cfg.out.exists()


def test_thin_parts_weigh_more_in_the_cross_entropy_and_the_bulk_does_not():
    masks = torch.zeros(1, 1, 24, 24)
    masks[..., 4:16, 4:16] = 1.0  # a handle
    masks[..., 9:11, 16:23] = 1.0  # a shaft two pixels wide
    weights = segmenter.thin_part_weights(masks, 2, 4.0)
    assert (weights[..., 9:11, 16:23] == 5.0).all() and (weights[..., 6:14, 6:14] == 1.0).all()
    assert (weights[masks == 0] == 1.0).all()
    logits = torch.full_like(masks, -1.0)  # the same wrong answer everywhere on the object
    plain, weighted = segmenter.pixel_bce(logits, masks), segmenter.pixel_bce(logits, masks, weights)
    bce = torch.nn.functional.binary_cross_entropy_with_logits(logits, masks, reduction="none")
    assert float(weighted - plain) == pytest.approx(4.0 * float(bce[..., 9:11, 16:23].sum()) / 24**2, rel=1e-5)
