"""Image-conditioned fields under the protocol (AFF-NeRF, PixelNeRF-M): encode the input views, render the
target cameras."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.data.dataset import ObjectData
from affnerf.eval.protocol import Prediction, TargetSet
from affnerf.model.inputs import dataset_views
from affnerf.model.config import RAYS_PER_CHUNK
from affnerf.model.views import render_view
from affnerf.predict.loading import LoadedModel


class ConditionedNeRFMethod:
    """A trained model of either kind; its name is the model's kind (``affnerf`` or ``pixelnerf``).

    Args:
        loaded: the model.
        chunk: rays per forward pass.
        fast: render with the object's occupancy grid (empty-space skipping).
    """

    def __init__(self, loaded: LoadedModel, chunk: int = RAYS_PER_CHUNK, fast: bool = True) -> None:
        self.loaded = loaded
        self.chunk = chunk
        self.fast = fast
        self.name = loaded.model.config.kind

    @torch.no_grad()
    def encode(self, obj: ObjectData, inputs: list[int]):
        """The object's encoding from its input views (AFF-NeRF averages the views' codes)."""
        model = self.loaded.model
        device = self.loaded.device
        images, intr, poses = dataset_views(obj, inputs, model.config.encoder_resolution)
        return model.encode_views(images.to(device), intr.to(device), poses.to(device))

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        encoding = self.encode(obj, inputs)
        model = self.loaded.model
        grid = model.occupancy(encoding) if self.fast else None
        views = [
            render_view(model, encoding, targets.intrinsics, pose, targets.background, self.chunk, grid)
            for pose in targets.poses
        ]
        return Prediction(np.stack([v.labels for v in views]), np.stack([v.rgb for v in views]))
