"""Which training options are refused, and why: combinations that only work together, and values out of range.

The trainer calls :func:`check_options` before it builds anything, so a bad command line costs one clear line and
writes nothing.
"""

from __future__ import annotations

from collections.abc import Mapping

from affnerf.errors import AffnerfError
from affnerf.train.config import TrainConfig

#: model kinds with image encoders (parameters named ``*encoder*``) for ``--optim.weight-decay`` to decay and
#: ``--optim.encoder-lr-scale`` to scale.
ENCODER_KINDS = ("affnerf", "pose-aware")

__all__ = ["check_mirror", "check_optimiser", "check_options", "check_surface_samples", "refuse_negative"]


def check_options(config: TrainConfig) -> None:
    """Raise :class:`AffnerfError` with one line when options that only work together are combined wrongly."""
    if config.view_consistency_weight > 0:
        if config.model.kind != "affnerf":
            raise AffnerfError(
                f"--view-consistency-weight needs global codes (--model.kind affnerf), not {config.model.kind!r}"
            )
        if config.objects_per_step < 2:
            raise AffnerfError("--view-consistency-weight needs at least 2 objects a step (--objects-per-step)")
    sigmas = (config.point_sigma_near, config.point_sigma_far)
    if config.points_weight > 0 and (
        config.points_per_object < 1
        or min(sigmas) < 0
        or not 0 <= config.point_part_balance <= 1
        or not 0 <= config.point_uniform_share <= 1
    ):
        raise AffnerfError(
            "--points-weight needs --points-per-object >= 1, point sigmas >= 0, --point-part-balance in [0, 1]"
            " and --point-uniform-share in [0, 1]"
        )
    if config.points_weight_final >= 0 and config.points_weight <= 0:
        raise AffnerfError("--points-weight-final needs --points-weight > 0 (the weight the schedule starts from)")
    if config.model.view_affordance_weight > 0 and config.input_jitter > 0:
        raise AffnerfError("--model.view-affordance-weight needs --input-jitter 0 (the crops' labels are not jittered)")
    check_optimiser(config)
    shares = (config.foreground_fraction, config.outline_fraction)
    if min(shares) < 0 or sum(shares) > 1 or config.outline_radius < 0:
        raise AffnerfError(
            "--foreground-fraction and --outline-fraction are shares >= 0 summing to at most 1 and "
            f"--outline-radius is >= 0, not {shares[0]}, {shares[1]} and {config.outline_radius}"
        )
    if not 0 <= config.edge_fraction <= config.foreground_fraction or config.edge_radius < 0:
        raise AffnerfError(
            f"--edge-fraction is a share of the --foreground-fraction rays (0 to {config.foreground_fraction}) and "
            f"--edge-radius >= 0, not {config.edge_fraction} and {config.edge_radius}"
        )
    check_surface_samples(config)
    check_mirror(config)
    if not 0 <= config.cut_input_weight <= 1:
        raise AffnerfError(f"--cut-input-weight is in [0, 1] (1 = every frame alike), not {config.cut_input_weight}")
    refuse_negative(
        {"checkpoint-every": config.checkpoint_every, "log-every": config.log_every, "val-every": config.val_every},
        "a number of steps (>= 0; 0 = only at the end)",
    )
    refuse_negative({"optim.warmup-steps": config.optim.warmup_steps}, "a number of steps (>= 0)")
    weights = {
        "mask-weight": config.mask_weight,
        "depth-weight": config.depth_weight,
        "termination-weight": config.termination_weight,
        "lovasz-weight": config.lovasz_weight,
    }
    refuse_negative(weights, "a weight (>= 0; 0 = off)")


def check_optimiser(config: TrainConfig) -> None:
    """Raise :class:`AffnerfError` with one line for an ``--optim.*`` value out of range, or one that acts on image
    encoders in a model without them."""
    if not 0.0 <= config.optim.ema_decay < 1.0:
        raise AffnerfError(f"--optim.ema-decay is 0 (no average) or in (0, 1), not {config.optim.ema_decay}")
    if config.optim.weight_decay < 0:
        raise AffnerfError(f"--optim.weight-decay is 0 (none) or positive, not {config.optim.weight_decay}")
    if config.optim.weight_decay > 0 and config.model.kind not in ENCODER_KINDS:
        raise AffnerfError(
            f"--optim.weight-decay decays the image encoders of {', '.join(ENCODER_KINDS)} models;"
            f" a {config.model.kind} model has none"
        )
    if config.optim.encoder_lr_scale <= 0:
        raise AffnerfError(f"--optim.encoder-lr-scale is positive, not {config.optim.encoder_lr_scale}")
    if config.optim.encoder_lr_scale != 1.0 and config.model.kind not in ENCODER_KINDS:
        raise AffnerfError(
            f"--optim.encoder-lr-scale scales the image encoders of {', '.join(ENCODER_KINDS)} models;"
            f" a {config.model.kind} model has none"
        )


def check_surface_samples(config: TrainConfig) -> None:
    """Refuse depth-guided sampling out of range, without fine samples to move, or for the models whose samples
    are placed along whole rays by their own sampler (Semantic-Ray, GSNeRF)."""
    if config.surface_sample_share == 0:
        return
    c = config
    if not (0 < c.surface_sample_share <= 1 and 0 < c.surface_sample_until <= 1 and c.surface_sample_sigma >= 0):
        raise AffnerfError(
            "--surface-sample-share and --surface-sample-until are in (0, 1] and --surface-sample-sigma >= 0, not "
            f"{c.surface_sample_share}, {c.surface_sample_until} and {c.surface_sample_sigma}"
        )
    if c.model.num_fine == 0 or c.model.kind in ("semantic-ray", "gsnerf"):
        raise AffnerfError(
            "--surface-sample-share needs fine samples (--model.num-fine > 0) and a model that samples each point "
            f"on its own (affnerf, pose-aware, pixelnerf), not --model.kind {c.model.kind} with "
            f"{c.model.num_fine} fine samples"
        )


def refuse_negative(options: Mapping[str, float], meaning: str) -> None:
    """Raise :class:`AffnerfError` with one line, ``--NAME is MEANING, not VALUE``, for the first of ``options``
    (command-line names without the dashes, and their values) that is below 0.

    Example:
        >>> refuse_negative({"log-every": -5}, "a number of steps")
        Traceback (most recent call last):
        affnerf.errors.AffnerfError: --log-every is a number of steps, not -5
    """
    for name, value in options.items():
        if value < 0:
            raise AffnerfError(f"--{name} is {meaning}, not {value}")


def check_mirror(config: TrainConfig) -> None:
    """Refuse ``--mirror-fraction`` outside [0, 1], without the 3D supervision points its planes are found from,
    or for a model kind other than the global-code one (the posed baselines also read the flipped views' cameras
    and pixels, a path no measurement or test covers)."""
    share = config.mirror_fraction
    if not 0 <= share <= 1:
        raise AffnerfError(f"--mirror-fraction is a chance in [0, 1], not {share}")
    if share > 0 and config.points_weight <= 0:
        raise AffnerfError("--mirror-fraction needs --points-weight > 0 (each object's plane comes from its points)")
    if share > 0 and config.model.kind != "affnerf":
        raise AffnerfError(f"--mirror-fraction needs global codes (--model.kind affnerf), not {config.model.kind!r}")
