"""AFF-NeRF with test-time inversion (``affnerf-fit``): the encoder's codes fitted to the input view and its camera
searched (:mod:`affnerf.predict.invert`), then rendered and meshed like ``affnerf``. Unposed, like AFF-NeRF: the
input view's pose is never read; its intrinsics are (a calibrated camera)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import torch

from affnerf.data.dataset import ObjectData
from affnerf.eval.methods.affnerf import ConditionedNeRFMethod, load_run
from affnerf.eval.registry import MethodContext, MethodSpec, register_method
from affnerf.model.affnerf import Codes
from affnerf.predict.invert import InversionConfig, InversionResult, dataset_crop_target, invert


class FittedAffNeRFMethod(ConditionedNeRFMethod):
    """AFF-NeRF whose codes of each object are fitted to its input views (one fit per view; several views'
    fitted codes are averaged). The last fits are kept in :attr:`results` for diagnostics."""

    def __init__(self, *args, inversion: InversionConfig | None = None, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.inversion = inversion or InversionConfig()
        self.name = "affnerf-fit"
        self.results: list[InversionResult] = []

    def encode(self, obj: ObjectData, inputs: list[int]) -> Codes:
        model = self.loaded.model
        size = model.config.encoder_resolution
        fits = []
        for view in inputs:
            codes = super().encode(obj, [view])
            target = dataset_crop_target(obj, view, size)
            config = replace(self.inversion, seed=self.inversion.seed + view)
            fits.append(invert(model, codes, target, np.asarray(self.loaded.background), config))
        self.results = fits
        return Codes(
            torch.stack([f.codes.shape for f in fits]).mean(0), torch.stack([f.codes.appearance for f in fits]).mean(0)
        )


def _build(context: MethodContext) -> FittedAffNeRFMethod:
    loaded = load_run(context, "affnerf", "affnerf-fit")
    return FittedAffNeRFMethod(loaded, context.chunk, context.fast, context.mesh_resolution)


register_method(
    MethodSpec(
        "affnerf-fit",
        _build,
        "AFF-NeRF with test-time inversion: codes and input camera fitted to the input view (CodeNeRF-style)",
        in_all=False,
    )
)
