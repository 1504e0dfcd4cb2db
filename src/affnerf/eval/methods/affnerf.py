"""AFF-NeRF under the protocol: encode the input view, render the target cameras."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.data.dataset import ObjectData
from affnerf.eval.protocol import Prediction, TargetSet
from affnerf.model.affnerf import Codes
from affnerf.model.views import render_view
from affnerf.predict.loading import LoadedModel
from affnerf.train.validate import encoder_input


class AffNeRFMethod:
    """A trained AFF-NeRF. With several input views, their codes are averaged.

    Args:
        loaded: the model.
        chunk: rays per forward pass.
    """

    name = "affnerf"

    def __init__(self, loaded: LoadedModel, chunk: int = 1024) -> None:
        self.loaded = loaded
        self.chunk = chunk

    @torch.no_grad()
    def encode(self, obj: ObjectData, inputs: list[int]) -> Codes:
        """The object's codes from its input views (mean over views)."""
        model = self.loaded.model
        images = torch.cat([encoder_input(obj, i, model.config.encoder_resolution) for i in inputs])
        codes = model.encode(images.to(self.loaded.device))
        return Codes(codes.shape.mean(0, keepdim=True), codes.appearance.mean(0, keepdim=True))

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        codes = self.encode(obj, inputs)
        views = [
            render_view(self.loaded.model, codes, targets.intrinsics, pose, targets.background, self.chunk)
            for pose in targets.poses
        ]
        return Prediction(np.stack([v.labels for v in views]), np.stack([v.rgb for v in views]))
