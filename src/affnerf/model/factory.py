"""Building a model from its configuration."""

from __future__ import annotations

from affnerf.model.affnerf import AffNeRF
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.pixelnerf import PixelNeRF


def build_model(config: ModelConfig, num_classes: int) -> ConditionedNeRF:
    """AFF-NeRF or the PixelNeRF-M baseline, as ``config.kind`` says."""
    if config.kind == "pixelnerf":
        return PixelNeRF(config, num_classes)
    return AffNeRF(config, num_classes)
