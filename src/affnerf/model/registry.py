"""Model kinds by name: ``ModelConfig.kind`` picks the class that :func:`build_model` instantiates.

A new kind (a field conditioned differently, say) is a :class:`~affnerf.model.base.ConditionedNeRF` subclass
taking ``(config, num_classes)``, added to :data:`MODEL_KINDS` with :func:`register_model` and to the ``kind``
literal of :class:`~affnerf.model.config.ModelConfig` (which the command line offers as choices).
"""

from __future__ import annotations

from typing import get_args, get_type_hints

from affnerf.errors import AffnerfError
from affnerf.model.affnerf import AffNeRF
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.gsnerf import GSNeRF
from affnerf.model.pixelnerf import PixelNeRF
from affnerf.model.pose_aware import PoseAwareNeRF
from affnerf.model.semantic_ray import SemanticRay

#: Kind name -> model class.
MODEL_KINDS: dict[str, type[ConditionedNeRF]] = {
    "affnerf": AffNeRF,
    "pixelnerf": PixelNeRF,
    "semantic-ray": SemanticRay,
    "gsnerf": GSNeRF,
    "pose-aware": PoseAwareNeRF,
}


def register_model(kind: str, cls: type[ConditionedNeRF]) -> None:
    """Make ``cls`` buildable as ``kind``; a name registered twice is an error."""
    if kind in MODEL_KINDS:
        raise ValueError(f"model kind {kind!r} is registered twice")
    MODEL_KINDS[kind] = cls


def config_kinds() -> tuple[str, ...]:
    """The kinds ``ModelConfig.kind`` accepts."""
    return get_args(get_type_hints(ModelConfig)["kind"])


def build_model(config: ModelConfig, num_classes: int) -> ConditionedNeRF:
    """The model ``config.kind`` names, with ``num_classes`` affordance classes.

    Raises:
        ValueError: for a kind no class is registered under.
        AffnerfError: for ``triplane`` conditioning, a ``view_affordance_weight``, ``encoders`` ``one``, a
            ``shape_pooling`` other than ``mean`` or a ``code_noise`` of another kind than ``affnerf`` (only
            AFF-NeRF's shape code can be decoded into planes, only its encoder labels pixels or pools into
            keypoints, only it has the two encoders that ``one`` merges and the two global codes the noise is added
            to), or a negative ``code_noise``; a ``code_kl_weight`` for another kind, or below zero.
    """
    if config.kind not in MODEL_KINDS:
        raise ValueError(f"unknown model kind {config.kind!r} (known: {', '.join(MODEL_KINDS)})")
    if config.conditioning == "triplane" and config.kind != "affnerf":
        raise AffnerfError(f"triplane conditioning decodes AFF-NeRF's shape code; a {config.kind} model has none")
    if config.view_affordance_weight > 0 and config.kind != "affnerf":
        raise AffnerfError(f"--model.view-affordance-weight labels AFF-NeRF's input crops, not a {config.kind} model's")
    if config.encoders == "one" and config.kind != "affnerf":
        raise AffnerfError(f"--model.encoders one merges AFF-NeRF's two encoders; a {config.kind} model has its own")
    if config.code_noise < 0:
        raise AffnerfError(f"--model.code-noise is a share of the codes' spread (>= 0), not {config.code_noise}")
    if config.code_noise > 0 and config.kind != "affnerf":
        raise AffnerfError(f"--model.code-noise perturbs AFF-NeRF's two global codes; a {config.kind} model has none")
    if config.code_kl_weight < 0:
        raise AffnerfError(f"--model.code-kl-weight weighs a KL divergence (>= 0), not {config.code_kl_weight}")
    if config.code_kl_weight > 0 and config.kind != "affnerf":
        raise AffnerfError(f"--model.code-kl-weight makes AFF-NeRF's codes variational; a {config.kind} model has none")
    if config.shape_pooling != "mean" and config.kind != "affnerf":
        raise AffnerfError(f"--model.shape-pooling pools AFF-NeRF's shape encoder; a {config.kind} model has none")
    return MODEL_KINDS[config.kind](config, num_classes)
