"""Training the object segmenter (:mod:`affnerf.model.segmenter`) on a dataset's renders pasted onto clutter.

The training split's objects (a few views each) are pasted onto photographs and dead-leaves clutter
(:mod:`affnerf.data.composite`) into a pool of synthetic photos at the network's size. Each step draws a batch from
the pool (fragments of other objects pasted into the background as distractors), flips it at random and changes its
colours (the whole photo, and the object on its own, with the encoders' jitter of :mod:`affnerf.train.augment`),
blur and noise, so lighting and camera quality do not decide the mask. The loss is binary cross-entropy plus a soft
Dice term (the object is often a small share of the photo). The validation split's objects, on the same kinds of
background, give the mask IoU logged while training; the photographs held out in
:data:`affnerf.data.composite.HELD_OUT_BACKGROUNDS` are never used.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional as F

from affnerf.data.composite import Cutout, cut_to_box, largest_component, photo_crop, photo_library, training_photo
from affnerf.data.dataset import Dataset
from affnerf.errors import AffnerfError
from affnerf.model.segmenter import (
    SEGMENTER_THRESHOLD,
    SalientSegmenter,
    Segmenter,
    SegmenterConfig,
    SegmenterEnsemble,
    build_segmenter,
    object_probability,
    read_segmenter,
    salient_segmenter,
    save_segmenter,
)
from affnerf.train.augment import blur_and_noise, jitter_colour
from affnerf.train.precision import Precision, forward_precision
from affnerf.train.schedule import cosine_fall

logger = logging.getLogger(__name__)


@dataclass
class SegmenterTrainConfig:
    """How to train the object segmenter.

    Attributes:
        data: dataset folder (``affnerf data generate`` or ``data import``); its ``train`` split is pasted.
        out: the weight file to write.
        steps: optimiser steps.
        batch: photos per step.
        lr: peak AdamW learning rate (cosine decay to 5 % of it).
        views_per_object: rendered views of each training object used.
        pool: synthetic photos made before training (drawn from with replacement, flipped and re-coloured each time).
        val_photos: validation photos (validation-split objects).
        jitter: strength of the colour, blur and noise changes (0 = none, 1 = the encoders' default ranges).
        seed: random seed of the pool and the steps.
        time_limit_min: stop after this many minutes (0 = no limit); the weights are written either way.
        init: a segmenter file to start from (its network shape is used), instead of random weights.
        init_salient: start from the salient-object model's weights (U²-Net-p, the optional extra
            ``affnerf[segment]``; the network's kind becomes ``u2netp``, its other fields are kept): a network that
            has seen real photographs, fine-tuned to the dataset's families. Use a small ``lr`` (1e-4) and an
            ``input_side`` that is a multiple of 32 whose three quarters are too (256).
        subjects: how many whole things to cut out of random crops of the background photographs with the
            salient-object model (the optional extra; none without it); half of the training photos get one pasted
            large behind the object (:func:`affnerf.data.composite.training_photo`), so that the subject of a busy
            photo (a person, a cup) is not taken for the object. 0 = none.
        precision: ``bf16`` runs each step's forward pass under bfloat16 autocast (weights and Adam state stay
            float32), about twice as fast for U²-Net-p on a CPU with bfloat16 instructions; ``fp32`` as before.
        hard_share: share of each batch drawn from the pool's hard photos (prioritised by loss, for a further stage
            of a trained segmenter): those are drawn with a probability proportional to the loss each photo had when
            last drawn (photos not drawn yet count as the mean of those that were), the rest of the batch uniformly
            as usual. 0 = every draw uniform (the earlier stages' rule, draw for draw).
        thin_weight: extra weight of the true mask's thin parts (a shaft, a bail, a temple of eyeglasses: where a
            square of side 2 × ``thin_radius`` × the photo's larger side does not fit in the mask) in every
            cross-entropy term: those pixels count ``1 + thin_weight`` times. They are a small share of the photo,
            so a network that drops them loses little loss and little IoU, but they carry the labels that tell a
            screwdriver from a bucket. 0 = none, as the shipped networks were trained: a stage at 4 found more of
            the thin parts but lost whole objects the shipped pair finds, so it was not kept
            (``benchmarks/results/segmenter_u2netp.md``, "Thin parts weighted").
        thin_radius: the half-side of that square, a share of the training photo's larger side.
        network: the network's shape.
    """

    data: Path
    out: Path
    steps: int = 3000
    batch: int = 16
    lr: float = 2e-3
    views_per_object: int = 4
    pool: int = 6000
    val_photos: int = 96
    jitter: float = 1.0
    seed: int = 0
    time_limit_min: float = 0.0
    init: Path | None = None
    init_salient: bool = False
    subjects: int = 0
    precision: Precision = "fp32"
    hard_share: float = 0.0
    thin_weight: float = 0.0
    thin_radius: float = 0.0125
    network: SegmenterConfig = SegmenterConfig()


def load_cutouts(dataset: Dataset, split: str, views: int, rng: np.random.Generator) -> list[Cutout]:
    """Cutouts of ``views`` random views of every object of ``split`` (mask: ``affordance > 0``)."""
    cutouts = []
    for entry in dataset.objects(split):
        obj = dataset.load_object(entry)
        for i in rng.permutation(len(obj.record.frames))[:views]:
            cut = cut_to_box(obj.rgb(int(i)), obj.affordance(int(i)) > 0)
            if cut is not None:
                cutouts.append(cut)
    if not cutouts:
        raise AffnerfError(f"{dataset.root}: no {split} objects to train the segmenter on")
    return cutouts


def subject_cutouts(photos: list[np.ndarray], count: int, rng: np.random.Generator) -> list[Cutout]:
    """Up to ``count`` whole things cut out of random 4:3 crops of ``photos`` (zoomed 1-2.5×): the largest region
    the salient-object model marks (p > 0.5) in each, kept when it covers 3-60 % of the crop (at most ``4 count``
    crops are tried). Empty (with a warning) when the model is not installed."""
    from affnerf.model.u2netp import SalientUnavailable

    try:
        model = salient_segmenter(SegmenterConfig(input_side=320))
    except SalientUnavailable as err:
        logger.warning("no subjects pasted: %s", err)
        return []
    cutouts = []
    for _ in range(4 * count if photos else 0):
        crop = photo_crop(rng, photos[rng.integers(len(photos))], (320, 240))
        mask = largest_component(object_probability(model, crop) > SEGMENTER_THRESHOLD)
        if 0.03 <= mask.mean() <= 0.6:
            cutouts.append(cut_to_box(crop, mask))
        if len(cutouts) == count:
            break
    return cutouts


def make_pool(
    cutouts: list[Cutout],
    photos: list[np.ndarray],
    count: int,
    size: tuple[int, int],
    rng: np.random.Generator,
    subjects: list[Cutout] = (),
) -> tuple[torch.Tensor, torch.Tensor]:
    """(count, 3, H, W) uint8 synthetic photos and (count, 1, H, W) bool masks at ``size`` = (W, H)."""
    images = torch.empty(count, 3, size[1], size[0], dtype=torch.uint8)
    masks = torch.empty(count, 1, size[1], size[0], dtype=torch.bool)
    for k in range(count):
        rgb, mask = training_photo(rng, cutouts[rng.integers(len(cutouts))], photos, size, cutouts, subjects)
        images[k] = torch.from_numpy(rgb).permute(2, 0, 1)
        masks[k, 0] = torch.from_numpy(mask)
    return images, masks


def augment_batch(
    images: torch.Tensor, masks: torch.Tensor, strength: float, g: torch.Generator
) -> tuple[torch.Tensor, torch.Tensor]:
    """(N, 3, H, W) float photos in 0..1 and (N, 1, H, W) float masks of a uint8/bool batch: flipped left-right at
    random, colours changed over the whole photo and over the object, blurred (half of them) and noised."""
    x, m = images.float() / 255.0, masks.float()
    flip = torch.rand(x.shape[0], generator=g) < 0.5
    x[flip], m[flip] = x[flip].flip(-1), m[flip].flip(-1)
    if strength > 0:
        x = jitter_colour(x, torch.ones_like(m), strength, g)
        x = blur_and_noise(jitter_colour(x, m, strength, g), strength, g)
    return x, m


def initial_segmenter(cfg: SegmenterTrainConfig) -> Segmenter:
    """The network training starts from: ``cfg.init``'s, the salient model's (``init_salient``) or a new one."""
    if cfg.init is not None:
        model = read_segmenter(Path(cfg.init))
        if isinstance(model, SegmenterEnsemble):
            raise AffnerfError(
                f"{cfg.init}: an ensemble of {len(model.members)} segmenters; --init takes one network: save one of "
                "its members (read_segmenter(FILE).members[k], save_segmenter) and start from that"
            )
        return model
    if not cfg.init_salient:
        return build_segmenter(cfg.network)
    return salient_segmenter(cfg.network)


def learning_rate(peak: float, step: int, steps: int) -> float:
    """The rate of ``step`` (0-based) of ``steps``: a linear warm-up over the first 5 % of the steps (at most 100;
    a pre-trained network's first Adam steps at full rate undo what it knew), then cosine decay to 5 % of ``peak``.

    Example:
        >>> [round(learning_rate(1.0, s, 1000), 3) for s in (0, 49, 500, 999)]
        [0.02, 1.0, 0.525, 0.05]
    """
    warm = min(100, steps // 20)
    if step < warm:
        return peak * (step + 1) / warm
    return cosine_fall(peak, 0.05 * peak, step / steps)


def thin_part_weights(masks: torch.Tensor, radius: int, weight: float) -> torch.Tensor:
    """(N, 1, H, W) pixel weights of (N, 1, H, W) 0/1 masks: ``1 + weight`` on the masks' thin parts (the pixels an
    opening by a square of side ``2 * radius + 1`` removes), 1 elsewhere.

    Example:
        >>> m = torch.zeros(1, 1, 12, 12); m[..., 2:10, 2:8] = 1; m[..., 5, 8:12] = 1
        >>> w = thin_part_weights(m, 1, 3.0)
        >>> w[0, 0, 5, 10].item(), w[0, 0, 5, 4].item(), w[0, 0, 0, 0].item()
        (4.0, 1.0, 1.0)
    """
    k = 2 * radius + 1
    opened = F.max_pool2d(-F.max_pool2d(-masks, k, 1, radius), k, 1, radius)
    return 1.0 + weight * masks * (1.0 - opened)


def pixel_bce(logits: torch.Tensor, masks: torch.Tensor, weights: torch.Tensor | None = None) -> torch.Tensor:
    """(N,) binary cross-entropy of (N, 1, H, W) logits against 0/1 masks, averaged over each photo's pixels, each
    pixel counted ``weights`` ((N, 1, H, W), or 1) times."""
    bce = F.binary_cross_entropy_with_logits(logits, masks, reduction="none")
    return (bce if weights is None else bce * weights).mean(dim=(1, 2, 3))


def photo_losses(logits: torch.Tensor, masks: torch.Tensor, weights: torch.Tensor | None = None) -> torch.Tensor:
    """(N,) binary cross-entropy (pixels weighted by ``weights``, see :func:`pixel_bce`) plus soft Dice
    (1 - 2|P∩M| / (|P| + |M|)) of each photo's (N, 1, H, W) logits against its 0/1 mask."""
    p = torch.sigmoid(logits)
    inter = (p * masks).sum(dim=(1, 2, 3))
    dice = 1.0 - (2.0 * inter + 1.0) / (p.sum(dim=(1, 2, 3)) + masks.sum(dim=(1, 2, 3)) + 1.0)
    return pixel_bce(logits, masks, weights) + dice


def step_losses(
    model: Segmenter, images: torch.Tensor, masks: torch.Tensor, weights: torch.Tensor | None = None
) -> torch.Tensor:
    """(N,) training loss of each photo of a batch: :func:`photo_losses` of the output, and for U²-Net-p also the
    mean binary cross-entropy of its six side outputs (its deep supervision); pixels weighted by ``weights``."""
    if not isinstance(model, SalientSegmenter):
        return photo_losses(model(images), masks, weights)
    fused, sides = model.side_logits(images)
    side_bce = torch.stack([pixel_bce(s.float(), masks, weights) for s in sides]).mean(dim=0)
    return photo_losses(fused.float(), masks, weights) + side_bce


def draw_batch(last_loss: torch.Tensor, batch: int, hard_share: float, g: torch.Generator) -> torch.Tensor:
    """(batch,) pool indices of one step: ``round(hard_share * batch)`` drawn with a probability proportional to
    ``last_loss`` ((pool,) the loss of each photo when last drawn, NaN before its first draw, which counts as the
    mean of the drawn ones), the rest uniformly (all of them while nothing has been drawn, or with no hard share:
    then exactly the draws of a uniform rule).

    Example:
        >>> last = torch.tensor([float("nan"), 0.0, 0.0, 4.0])
        >>> draw_batch(last, 4, 0.5, torch.Generator().manual_seed(0))[2:].tolist()
        [3, 3]
    """
    pool = last_loss.shape[0]
    drawn = ~torch.isnan(last_loss)
    hard = round(hard_share * batch) if drawn.any() else 0
    uniform = torch.randint(0, pool, (batch - hard,), generator=g)
    if not hard:
        return uniform
    weight = torch.where(drawn, last_loss, last_loss[drawn].mean()).clamp(min=0.0) + 1e-8
    return torch.cat([uniform, torch.multinomial(weight, hard, replacement=True, generator=g)])


@torch.no_grad()
def mean_mask_iou(model: Segmenter, images: torch.Tensor, masks: torch.Tensor, chunk: int = 32) -> float:
    """Mean IoU of the thresholded (p > 0.5) masks of uint8 photos against bool masks, at the network's size."""
    was_training = model.training
    model.eval()
    ious = []
    for s in range(0, images.shape[0], chunk):
        pred = model(images[s : s + chunk].float() / 255.0) > 0
        truth = masks[s : s + chunk]
        inter = (pred & truth).sum(dim=(1, 2, 3)).float()
        union = (pred | truth).sum(dim=(1, 2, 3)).float().clamp(min=1.0)
        ious.append(inter / union)
    model.train(was_training)
    return float(torch.cat(ious).mean())


def network_size(config: SegmenterConfig) -> tuple[int, int]:
    """(W, H) of the training photos: a 4:3 landscape of the network's input side (multiples of ``config.multiple``)."""
    m = config.multiple
    return config.input_side, int(round(config.input_side * 0.75 / m)) * m


def train_segmenter(cfg: SegmenterTrainConfig) -> dict:
    """Train the segmenter and write it to ``cfg.out``; returns the training record (also stored in the file).

    Raises:
        AffnerfError: a hard share outside [0, 1] (before anything is made or written).
    """
    if not 0.0 <= cfg.hard_share <= 1.0:
        raise AffnerfError(f"--hard-share must lie in [0, 1] (got {cfg.hard_share})")
    torch.manual_seed(cfg.seed)
    rng, g = np.random.default_rng(cfg.seed), torch.Generator().manual_seed(cfg.seed)
    model = initial_segmenter(cfg)
    dataset, size, photos = Dataset.open(cfg.data), network_size(model.config), photo_library()
    start = time.perf_counter()
    subjects = subject_cutouts(photos, cfg.subjects, rng) if cfg.subjects else []
    cutouts = load_cutouts(dataset, "train", cfg.views_per_object, rng)
    train = make_pool(cutouts, photos, cfg.pool, size, rng, subjects)
    val = make_pool(load_cutouts(dataset, "val", 2, rng), photos, cfg.val_photos, size, rng, subjects)
    logger.info("pool of %d photos (+%d validation) in %.0f s", cfg.pool, cfg.val_photos, time.perf_counter() - start)
    model.train()
    thin_px = max(1, round(cfg.thin_radius * max(size)))
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=1e-4)
    curve, step, loss = [], 0, torch.zeros(())
    last_loss = torch.full((cfg.pool,), float("nan"))
    while step < cfg.steps:
        if cfg.time_limit_min and time.perf_counter() - start > 60 * cfg.time_limit_min:
            break
        for group in opt.param_groups:
            group["lr"] = learning_rate(cfg.lr, step, cfg.steps)
        pick = draw_batch(last_loss, cfg.batch, cfg.hard_share, g)
        x, m = augment_batch(train[0][pick], train[1][pick], cfg.jitter, g)
        weights = thin_part_weights(m, thin_px, cfg.thin_weight) if cfg.thin_weight else None
        with forward_precision(cfg.precision, x.device):
            losses = step_losses(model, x, m, weights)
        loss = losses.mean()  # photos of a batch have one size: the cross-entropy is the mean over all its pixels
        last_loss[pick] = losses.detach().float()
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        step += 1
        if step % 250 == 0 or step == cfg.steps:
            minutes, iou = round((time.perf_counter() - start) / 60, 2), round(mean_mask_iou(model, *val), 4)
            curve.append(
                {"step": step, "minutes": minutes, "loss": round(float(loss.detach()), 4), "val_mask_iou": iou}
            )
            logger.info("%s", curve[-1])
            partial = {"steps_done": step, "curve": curve, "partial": True}
            save_segmenter(model.eval(), Path(cfg.out), partial)
            model.train()
    record = {"config": {k: str(v) for k, v in asdict(cfg).items()}, "steps_done": step, "curve": curve,
              "minutes": round((time.perf_counter() - start) / 60, 2), "backgrounds": len(photos),
              "subjects": len(subjects)}  # fmt: skip
    save_segmenter(model.eval(), Path(cfg.out), record)
    return record
