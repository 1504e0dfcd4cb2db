"""Training configuration: typed dataclasses, the ``paper`` and ``small`` presets, and their JSON form.

A run folder keeps the fully resolved config (``config.json``), so a run can be reproduced from its folder
alone: ``affnerf train --data DIR --out RUN2 --config-file RUN/config.json``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

from affnerf.errors import AffnerfError, input_error
from affnerf.fileio import read_json_file
from affnerf.model.config import RAYS_PER_CHUNK, ModelConfig
from affnerf.train.precision import Precision


@dataclass(frozen=True)
class OptimConfig:
    """Adam with a learning-rate schedule (:func:`affnerf.train.schedule.learning_rate`).

    Attributes:
        lr: learning rate at the start of the decay (the peak, after any warm-up).
        lr_final: learning rate reached at the last step.
        schedule: how the rate falls from ``lr`` to ``lr_final``: ``exponential`` (a constant factor a step, the
            ``paper`` preset) or ``cosine`` (half a cosine: slow at first, so more steps at a high rate; the
            ``small`` preset, at a peak of 2e-3 after 300 warm-up steps: benchmarks/results/learning_rate_schedule.md).
        warmup_steps: steps over which the rate first rises linearly to ``lr`` (0 = none; at most a tenth of the
            run's ``steps`` are used, so a short run of a preset still decays); the decay takes the steps after.
        grad_clip: clip the gradient norm to this (0 = no clipping).
        ema_decay: keep an exponential moving average of the weights with this decay per step (0 = none; e.g.
            0.999 averages about the last thousand steps; :mod:`affnerf.train.ema`). Checkpoints then hold it
            beside the weights, and predict, eval and ``--init-from`` use it.
        weight_decay: decoupled weight decay (AdamW) on the image encoders' convolution and linear weights, the
            part of the model that fits its training objects better than new ones (benchmarks/results/
            code_oracle_shipped.md); the field, biases and normalisation scales never decay. 0 = plain Adam, the
            presets' (benchmarks/results/weight_decay.md).
        encoder_lr_scale: the image encoders' learning rate is this times the schedule's (warm-up and decay
            alike); the field keeps the schedule's own. Beyond the paper: the encoders are a convolutional network
            and the field an MLP, and one rate need not suit both. 1 = one rate for all, the presets'.
    """

    lr: float = 5e-4
    lr_final: float = 5e-5
    schedule: Literal["exponential", "cosine"] = "exponential"
    warmup_steps: int = 0
    grad_clip: float = 0.0
    ema_decay: float = 0.0
    weight_decay: float = 0.0
    encoder_lr_scale: float = 1.0


@dataclass(frozen=True)
class TrainConfig:
    """Everything a training run depends on.

    Attributes:
        data: dataset folder (``dataset.json``).
        out: run folder (config, checkpoints, TensorBoard logs, metrics).
        config: the preset the other values start from: ``paper`` (conventions §4) or ``small`` (2 CPU cores).
        steps: total steps of the run; a resumed run stops at the same total.
        resume: continue from the last checkpoint in ``out``.
        device: ``auto`` (CUDA when available), ``cpu`` or ``cuda``.
        seed: seed of initialisation, data order and sampling.
        model: architecture and ray sampling.
        optim: optimiser and learning-rate schedule.
        objects_per_step: objects per step and per process (each with its own encoded view). 16 instead of the
            ``small`` preset's 8 (at 256 points each) is ahead step for step from scratch and level at equal time
            (objects_per_step.md); at the shipped model's budget level on val40 and test64 and behind on 192 fresh
            objects (mIoU −0.010, object mIoU −0.029; retrain_objects_per_step.md).
        input_views: views encoded per object (1 for AFF-NeRF; 3 for the multi-view PixelNeRF baseline).
        rays_per_step: rays per step and per process.
        foreground_fraction: share of rays drawn on the object (the rest near it, ``outline_fraction``, or uniform
            over the image). 0.8 instead of 0.5, with no rays near the outline, taught the labels inside the object
            a little better and the outline worse (validation mIoU −0.038, PSNR −2 dB;
            benchmarks/results/foreground_fraction.md).
        outline_fraction: share of rays drawn near the object, taken from the uniform ones: an object pixel moved by
            up to ``outline_radius`` pixels along each image axis, so they teach the outline from both sides (0 =
            off, the paper). The ``small`` preset draws 0.4 so (0.5 on the object, 0.1 uniform): against 0.5 / 0 /
            0.5 at equal steps, validation mIoU +0.012 / +0.014 on two seeds, PSNR +0.5 dB, 3D affordance mIoU
            +0.02 / +0.05 (benchmarks/results/outline_rays.md); a share of 0.25 was behind it on both splits
            (benchmarks/results/outline_share.md).
        outline_radius: half-width in pixels of the training images (after ``image_scale``) of that band. The
            preset's 3; 6 raised 2D mIoU, PSNR and F@1cm a little and cost 0.035-0.057 3D affordance mIoU
            (benchmarks/results/outline_share.md, one seed).
        edge_fraction: share of rays drawn near the edges between parts inside the object (an object pixel with
            an object pixel of another class among its neighbours, moved by up to ``edge_radius`` pixels along
            each image axis), taken from the ``foreground_fraction`` ones, so the labels are taught where they
            change and on thin parts (0 = none, the draws as before). 0.1 and 0.2 at radius 1 were level on mIoU
            and behind on object mIoU, MPA, F@1cm and 3D labels from scratch (benchmarks/results/part_edges.md).
        edge_radius: half-width in pixels of the training images of that band.
        cut_input_weight: how much a frame whose object touches the image border (and may be cut off by it)
            counts, against a frame that shows the whole object, when a step chooses the view its encoders see
            (rays still come from every other view). 1 = every frame alike (the paper); 0 = only whole views where
            the object has enough of them. Cut inputs are common in the procedural data (41 % of cabinet frames, a
            quarter of buckets' and eyeglasses') and the shipped model predicts worse from them (−0.035 mIoU against
            the same object's whole views). 0 was behind the preset from scratch on two seeds (val40 mIoU −0.009 /
            −0.001, test64 −0.003 / −0.009; test cabinets, five of eight seen cut, −0.077 / −0.038): the model needs
            cut views in training to read cut ones at test time (benchmarks/results/cut_inputs.md).
        mirror_fraction: chance that an object's encoded view is flipped left-right in a step, its rays and 3D points
            mirrored across the vertical plane through the origin it is most nearly symmetric about, so the flip
            shows the same object from another side, or its mirror image in its category's orientation
            (:mod:`affnerf.train.mirror`; the flip augmentation of image networks, made exact for a model that
            predicts in the object's frame). Beyond the paper; needs 3D supervision (the plane is found from the
            point sets) and global codes. 0 = never (the draws as before). 0.5 from scratch on two seeds was level
            with the preset's five runs on both splits (benchmarks/results/mirror_views.md).
        affordance_weight: lambda, the weight of the affordance cross-entropy (paper 4e-4; Semantic-NeRF 4e-2).
        affordance_balance: class balancing of the affordance cross-entropy: each class weighted by its pixel
            frequency in the training frames to the power -``affordance_balance`` (0 = plain CE, the paper; 0.5 =
            square root of inverse frequency, so thin parts such as blades and handles count more).
        mask_weight: weight of the BCE between each rendered ray's opacity and the object mask (0 = off, the paper).
        depth_weight: weight of the L1 between each object ray's rendered and true z-depth in metres (0 = off, the
            paper); uses the dataset's depth maps. It thickens outlines (benchmarks/results/fine_tune_losses.md).
        termination_weight: weight of the mean distance in metres between where each object ray's rendering weight
            lies and the true surface, Σ w·|t − depth| (0 = off, the paper): places density on the surface
            without the depth L1's push towards opacity. At 1.0 from the first step, beside the ``small`` preset on
            two seeds, mIoU +0.016 / +0.020 (val40) and +0.012 / +0.024 (test64), PA and PSNR up, object mIoU
            −0.003 to −0.022 (benchmarks/results/termination_scratch.md), for 0.6 % more time a step
            (termination_step_cost.json). Trained the shipped model's way (34,000 steps of two processes) it was
            mixed: val40 mIoU +0.017 and F@1cm +0.049, test64 mIoU −0.020 and object mIoU −0.040, pens −0.095 /
            −0.094 (retrain_termination.md), though a second seed of the preset itself lands as low on test64
            (0.621, pens' caps lost too; retrain_seed1.md). On two full-budget seeds each it is ahead on val40
            (mean mIoU +0.011) and behind on the 64 test objects (−0.011, object mIoU −0.026;
            retrain_termination_seed1.md). With 16 objects a step, ahead of the preset at its time on three seeds
            (objects_termination.md) and mixed again at full budget (val40 mIoU +0.006, test64 −0.006, object mIoU
            −0.030; retrain_objects_termination.md); so not in the preset.
        lovasz_weight: weight of the Lovász-softmax loss (:func:`affnerf.train.loss.lovasz_softmax`, a surrogate of
            each class's intersection over union in the step's batch) relative to the cross-entropy it joins: the
            rendered rays' at ``affordance_weight`` times this, the 3D points' at their affordance weight times this
            (0 = off, the paper). Beyond the paper: the CE is a mean over pixels, where small parts count little;
            this is a mean over classes, as mIoU and MPA are. At 1.0 as a further stage of the shipped weights, MPA
            +0.011 / +0.012 and object mIoU +0.010 / +0.014 (val40 / test64) at level mIoU
            (benchmarks/results/lovasz_stage.md); from scratch on two seeds MPA +0.002 to +0.013, mIoU −0.014 to
            +0.001, F@1cm down to −0.021 (lovasz_scratch.md). With ``termination_weight`` 1.0 it was ahead of the
            preset at 13,000 steps on two seeds (termination_lovasz.md) but behind the shipped weights at their
            34,000 steps of two processes (mIoU −0.004 val40, −0.018 test64, pens' caps lost;
            retrain_termination_lovasz.md); so not in the preset.
        view_consistency_weight: weight of the agreement between the codes of two views of each training object
            (0 = off, the paper): each object also encodes a second random view, and the squared distance between
            its codes and the first view's, over the spread of the step's codes (:func:`affnerf.train.loss.
            code_consistency`, shape and appearance codes alike), is added at this weight; only the first view's
            codes render. Beyond the paper, so that one object predicted from different photos agrees with itself.
            Global-code models only (``--model.kind affnerf``), at least 2 objects a step.
        input_jitter: strength of the random colour, framing, blur and noise changes to the encoders' crops
            (:mod:`affnerf.train.augment`; 0 = off, the paper; 1 = the documented ranges). From scratch at the
            shipped budget, 0.5 labels the inside of objects better and steadier over input views, but costs colour,
            3D labels and mIoU on fresh objects, so the presets keep 0 (benchmarks/results/retrain_input_jitter.md).
        points_weight: weight of the 3D supervision from each training object's ``mesh.ply`` (0 = off, the
            paper's loss; conventions §4): occupancy BCE of both fields at ``points_per_object`` points per object,
            plus ``point_affordance_weight`` times their affordance cross-entropy.
        points_weight_final: with a value >= 0, μ moves in a straight line from ``points_weight`` at the first
            step to this value at the last (:func:`affnerf.train.schedule.points_weight`); negative (the default):
            ``points_weight`` throughout. Beyond the paper, for a heavy 3D term early or late in a stage.
        points_per_object: supervision points drawn per object and step from its cached point set.
        point_affordance_weight: weight of the points' affordance cross-entropy relative to their occupancy BCE.
        point_distance_weight: with a signed-distance field (``--model.geometry sdf``), weight of the points'
            L1 between the field's distance and the true one, both clamped to the truncation
            (:data:`affnerf.train.points.DISTANCE_TRUNCATION`) and divided by it, relative to their occupancy BCE;
            ignored by density fields.
        point_sigma_near: noise sigma (m) of the first half of the near-surface points of each point set. From
            scratch on two seeds against the presets' 5 mm (results/point_sigma.md): 2.5 mm behind on val40 (mIoU
            -0.013 both), 10 mm level on mIoU and behind inside the object (object mIoU -0.013 to -0.021, MPA
            -0.009 to -0.014 in all four pairs).
        point_sigma_far: noise sigma (m) of the second half. 30 mm and 10 mm against the presets' 20, two seeds
            each: behind inside the object in all four pairs each (results/point_sigma.md).
        point_part_balance: how the near-surface points are spread over the object's affordance parts: 0 by area
            (Occupancy Networks' sampling), 1 the same share for every part however small its surface (a bail, a
            handle), in between each face's area times its part's area to the power -b
            (:func:`affnerf.train.points.part_face_weights`). Beyond the paper; off in both presets: as a further
            stage it moved neither the 2D nor the 3D scores nor the part grasps (results/part_balance.md).
        point_uniform_share: the share of each point set drawn uniformly over the scene cube (Occupancy Networks
            and IF-Net draw such a share beside the near-surface points); the rest is split between the two sigmas.
            0.1 against the presets' quarter, two seeds from scratch: one ahead, one behind, F@1cm behind in all four
            pairs (results/point_sigma.md).
        surface_sample_share: share of the fine samples of each ray that meets the object drawn around its true
            depth from the dataset's depth maps instead of from the coarse weights, at the first step (0 = off,
            the paper; :class:`affnerf.rendering.samplers.SurfaceGuide`). Beyond the paper: depth-guided sampling
            (DS-NeRF, Dense Depth Priors) evaluates the field at the surface, thin parts included, before the
            coarse weights know where it is. It falls in a straight line to 0 at ``surface_sample_until`` of the
            run, so the end of training samples as inference does. Needs fine samples. At 0.5 from scratch on two
            seeds, level on mIoU with the ``small`` preset, behind on 3D affordance mIoU (−0.026 / −0.013) and no
            faster early on: its 3D supervision already teaches the surface (benchmarks/results/surface_samples.md);
            so off in both presets.
        surface_sample_sigma: standard deviation in metres of those draws along the ray.
        surface_sample_until: fraction of the run's steps after which no sample is drawn so, in (0, 1].
        image_scale: training resolution as a fraction of the dataset's images.
        categories: comma-separated categories to train on (empty = all of the train split).
        checkpoint_every: steps between checkpoints (0 = only at the end of the run and when out of time).
        keep_checkpoints: how many recent checkpoints to keep.
        log_every: steps between logged scalars (0 = only at the last step).
        val_every: steps between validation renders (0 = never).
        val_objects: validation objects rendered each time.
        val_scale: resolution of validation renders as a fraction of the dataset's images.
        chunk: rays per forward pass when rendering whole images.
        cache_dir: where decoded training frames are kept (default: ``<out>/cache``).
        progress: show a progress bar.
        stop_at: end this invocation after this step with a checkpoint, as though interrupted; ``--resume``
            continues to ``steps`` (0 = run to the end).
        time_limit: end this invocation after this many minutes with a checkpoint (0 = no limit); for machines
            lent in short slots: rerun with ``--resume`` until done.
        precision: arithmetic of the forward pass, ``fp32`` (the paper) or ``bf16`` (autocast to bfloat16; weights,
            gradients and Adam state stay float32): see :mod:`affnerf.train.precision` and
            benchmarks/results/precision.md for its speed and quality.
        init_from: start from the weights of this checkpoint (a ``.pt`` file, the shipped model's included, or a
            run folder: its last checkpoint) instead of the seed's initialisation; the architecture must match,
            except that a concatenating field may start a FiLM one (``--model.conditioning film``; exact, the
            modulation starts at zero), a model without the pixel-labelling head one with it, and the encoders'
            crop side (``--model.encoder-resolution``) may differ (they pool globally). The optimiser, the step
            count and the learning-rate schedule start afresh (fine-tuning, or a second stage with its own
            schedule). Ignored when resuming (the run's own checkpoint wins).
    """

    data: Path
    out: Path
    config: Literal["paper", "small"] = "paper"
    steps: int = 200_000
    resume: bool = False
    device: Literal["auto", "cpu", "cuda"] = "auto"
    seed: int = 0
    model: ModelConfig = field(default_factory=ModelConfig)
    optim: OptimConfig = field(default_factory=OptimConfig)
    objects_per_step: int = 4
    input_views: int = 1
    rays_per_step: int = 1024
    foreground_fraction: float = 0.5
    outline_fraction: float = 0.0
    outline_radius: int = 3
    edge_fraction: float = 0.0
    edge_radius: int = 1
    cut_input_weight: float = 1.0
    mirror_fraction: float = 0.0
    affordance_weight: float = 4e-4
    affordance_balance: float = 0.0
    mask_weight: float = 0.0
    depth_weight: float = 0.0
    termination_weight: float = 0.0
    lovasz_weight: float = 0.0
    view_consistency_weight: float = 0.0
    input_jitter: float = 0.0
    points_weight: float = 0.0
    points_weight_final: float = -1.0
    points_per_object: int = 1024
    point_affordance_weight: float = 1.0
    point_distance_weight: float = 1.0
    point_sigma_near: float = 0.005
    point_sigma_far: float = 0.02
    point_part_balance: float = 0.0
    point_uniform_share: float = 0.25
    surface_sample_share: float = 0.0
    surface_sample_sigma: float = 0.01
    surface_sample_until: float = 0.5
    image_scale: float = 1.0
    categories: str = ""
    checkpoint_every: int = 2000
    keep_checkpoints: int = 3
    log_every: int = 50
    val_every: int = 5000
    val_objects: int = 2
    val_scale: float = 0.25
    chunk: int = RAYS_PER_CHUNK
    cache_dir: Path | None = None
    progress: bool = True
    stop_at: int = 0
    time_limit: float = 0.0
    precision: Precision = "fp32"
    init_from: Path | None = None


#: The paper's configuration (conventions §4): two ResNet18s, codes of 32, PE 10/4, 64 + 128 samples over the full
#: [0.1, 1.5] m range, 1024 rays a step, Adam at 5e-4, lambda 4e-4, 400x300 images.
PAPER = TrainConfig(data=Path("."), out=Path("."))

#: For 2 CPU cores, chosen by measurement (benchmarks/README.md, results/small_config.json): quarter-width
#: encoders on 64-pixel crops, a 4-layer 64-wide field, 24 + 24 samples inside the canonical cube, 256 rays over
#: 8 objects a step with 512 supervision points each (16 objects a step in all on the shipped model's two processes),
#: training at a quarter of the dataset's resolution, lambda 4e-2; beyond the paper, 3D supervision from the training
#: meshes at weight 0.1 (results/ablation_ladder.md) and a signed-distance field whose density is VolSDF's Laplace
#: CDF of it (results/sdf_geometry.md: +0.044 validation mIoU, +0.065 F@1cm at equal time); the other options of the
#: quality work, FiLM, mask/depth losses, class balancing, input jitter and triplanes, stay off: they did not pay at
#: equal time. More objects a step at the same rays and points pays at equal time (results/batch_shape.md: 16
#: objects 0.607 against 4 objects' 0.565 validation mIoU); 34,000 steps are 81 minutes of two single-threaded
#: processes (torchrun) on a 2-core VM with AVX-512 (results/retrain_keypoints.md: the shipped model since
#: 2026-12-05). One field places its own fine samples (coarse_field "shared"): a step 17-23 % cheaper, the same
#: learning per step (results/shared_field.md, two seeds). Of a step's rays 40 % are drawn near the object's outline
#: instead of uniformly (results/outline_rays.md, two seeds). The shape encoder also codes where its features peak
#: in the crop (shape_pooling "keypoints", a spatial soft-argmax; results/shape_pooling.md, two seeds: +0.015 mIoU,
#: +0.019 F@1cm on average over validation and test objects at equal steps and time).
SMALL = replace(
    PAPER,
    config="small",
    steps=34_000,
    model=ModelConfig(
        encoder_width=0.25,
        encoder_resolution=64,
        field_width=64,
        field_depth=4,
        color_width=32,
        affordance_width=32,
        num_coarse=24,
        num_fine=24,
        clip_to_cube=True,
        geometry="sdf",
        coarse_field="shared",
        shape_pooling="keypoints",
    ),
    optim=OptimConfig(lr=2e-3, lr_final=2e-5, schedule="cosine", warmup_steps=300),
    objects_per_step=8,
    rays_per_step=256,
    outline_fraction=0.4,
    affordance_weight=4e-2,
    points_weight=0.1,
    points_per_object=512,
    image_scale=0.25,
    checkpoint_every=500,
    log_every=50,
    val_every=2000,
    val_scale=0.5,
)


PRESETS: dict[str, TrainConfig] = {"paper": PAPER, "small": SMALL}


def for_model_kind(config: TrainConfig) -> TrainConfig:
    """``config`` with the AFF-NeRF-only model options a preset sets put back to the paper's for another kind of
    model, which has no shape encoder to apply them to: ``shape_pooling`` (the ``small`` preset's ``keypoints``), so
    ``--config small --model.kind pixelnerf`` trains the baseline and records what it trained.

    Example:
        >>> for_model_kind(replace(SMALL, model=replace(SMALL.model, kind="pixelnerf"))).model.shape_pooling
        'mean'
        >>> for_model_kind(SMALL).model.shape_pooling
        'keypoints'
    """
    if config.model.kind == "affnerf":
        return config
    return replace(config, model=replace(config.model, shape_pooling="mean"))


def preset(name: str, data: Path, out: Path) -> TrainConfig:
    """A preset with the run's data and output folders."""
    if name not in PRESETS:
        raise AffnerfError(f"unknown config {name!r} (known: {', '.join(PRESETS)})")
    return replace(PRESETS[name], data=Path(data), out=Path(out))


def config_to_json(config: TrainConfig) -> dict[str, Any]:
    """The config as nested plain JSON."""

    def plain(value: Any) -> Any:
        if dataclasses.is_dataclass(value):
            return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
        if isinstance(value, Path):
            return str(value)
        return value

    return plain(config)


def config_from_json(data: dict[str, Any], path: Path) -> TrainConfig:
    """Rebuild a :class:`TrainConfig` from :func:`config_to_json` output (``path`` names it in errors)."""
    try:
        model = ModelConfig(**data.get("model", {}))
        optim = OptimConfig(**data.get("optim", {}))
        top = {k: v for k, v in data.items() if k not in ("model", "optim")}
        for key in ("data", "out", "cache_dir", "init_from"):
            if top.get(key) is not None:
                top[key] = Path(top[key])
        return TrainConfig(**top, model=model, optim=optim)
    except TypeError as exc:
        raise input_error(path, f"not a training config of this version ({exc})") from None


def read_config(path: Path) -> TrainConfig:
    """Read a run's ``config.json``."""
    path = Path(path)
    return config_from_json(read_json_file(path), path)
