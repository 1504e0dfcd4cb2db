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
from affnerf.predict.carve import CARVE_RESOLUTION, SilhouetteView, carve
from affnerf.predict.invert import InversionConfig, InversionResult, dataset_crop_target, invert
from affnerf.rendering.grid import OccupancyGrid


class FittedAffNeRFMethod(ConditionedNeRFMethod):
    """AFF-NeRF whose codes of each object are fitted to its input views (one fit per view; several views'
    fitted codes are averaged). The last fits are kept in :attr:`results` for diagnostics. With ``carve_margin``
    (None: off), the object is carved by the input views' silhouettes at their fitted cameras
    (:mod:`affnerf.predict.carve`)."""

    def __init__(
        self, *args, inversion: InversionConfig | None = None, carve_margin: float | None = None, **kwargs
    ) -> None:
        super().__init__(*args, **kwargs)
        self.inversion = inversion or InversionConfig()
        self.carve_margin = carve_margin
        self.name = "affnerf-fit"
        self.results: list[InversionResult] = []
        self.silhouettes: list[SilhouetteView] = []

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
        self.silhouettes = [
            SilhouetteView(t.mask > 0.5, t.intrinsics, f.camera)
            for t, f in zip((dataset_crop_target(obj, v, CARVE_RESOLUTION) for v in inputs), fits, strict=True)
        ]
        return Codes(
            torch.stack([f.codes.shape for f in fits]).mean(0), torch.stack([f.codes.appearance for f in fits]).mean(0)
        )

    def build_grid(self, encoding: object) -> OccupancyGrid:
        grid = super().build_grid(encoding)
        if self.carve_margin is None or not self.silhouettes:
            return grid
        return carve(grid, self.silhouettes, self.carve_margin)


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
