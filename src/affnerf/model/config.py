"""Model configuration: the architecture and how rays are sampled (GUIDE 4)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal


@dataclass(frozen=True)
class ModelConfig:
    """Architecture and ray sampling.

    Attributes:
        kind: ``affnerf`` (global shape and appearance codes, GUIDE 4) or ``pixelnerf`` (the PixelNeRF-M
            baseline: pixel-aligned features projected with the input cameras).
        code_dim: size of the shape code and of the appearance code.
        encoder_width: channel multiplier of the two ResNet18 encoders (1.0 = standard ResNet18).
        encoder_resolution: side of the square object crop the encoders see, pixels.
        field_width: hidden width of the field's position trunk.
        field_depth: number of trunk layers.
        color_width: hidden width of the colour head.
        affordance_width: hidden width of the affordance head.
        pe_xyz: positional-encoding frequencies of positions.
        pe_dir: positional-encoding frequencies of view directions.
        num_coarse: stratified samples per ray (coarse field).
        num_fine: hierarchical samples per ray (fine field), added to the coarse ones.
        near: start of every ray, metres.
        far: end of every ray, metres.
        clip_to_cube: sample only where rays cross the canonical cube [-0.25, 0.25]^3 (rays that miss it render
            background without evaluating the field); False samples the whole [near, far] like vanilla NeRF.
    """

    kind: Literal["affnerf", "pixelnerf"] = "affnerf"
    code_dim: int = 32
    encoder_width: float = 1.0
    encoder_resolution: int = 224
    field_width: int = 256
    field_depth: int = 8
    color_width: int = 128
    affordance_width: int = 128
    pe_xyz: int = 10
    pe_dir: int = 4
    num_coarse: int = 64
    num_fine: int = 128
    near: float = 0.1
    far: float = 1.5
    clip_to_cube: bool = False
