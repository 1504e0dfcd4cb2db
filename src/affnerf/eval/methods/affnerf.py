"""Image-conditioned fields under the protocol (AFF-NeRF, PixelNeRF-M): encode the input views, render the
target cameras."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.data.dataset import ObjectData
from affnerf.errors import AffnerfError
from affnerf.eval.protocol import Prediction, TargetSet
from affnerf.eval.registry import MethodContext, MethodSpec, register_method
from affnerf.model.config import RAYS_PER_CHUNK
from affnerf.model.inputs import dataset_views
from affnerf.model.views import render_view
from affnerf.predict.loading import LoadedModel, load_model
from affnerf.predict.predictor import pick_device


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


def load_run(context: MethodContext, kind: str, method: str) -> LoadedModel:
    """The run of ``context`` for ``method``, checked to be a ``kind`` model trained with the dataset's affordance
    classes.

    Raises:
        AffnerfError: naming the checkpoint, when it is another kind of model or has other classes.
    """
    loaded = load_model(context.run, pick_device(context.device))
    found = loaded.model.config.kind
    if found != kind:
        raise AffnerfError(f"{loaded.path}: method {method} needs a run of kind {kind}, this run is of kind {found}")
    if loaded.classes != context.dataset.affordance_classes:
        raise AffnerfError(
            f"{loaded.path}: trained with other affordance classes than {context.dataset.root / 'dataset.json'}"
        )
    return loaded


def _build(kind: str):
    return lambda context: ConditionedNeRFMethod(load_run(context, kind, kind), context.chunk, context.fast)


register_method(
    MethodSpec("affnerf", _build("affnerf"), "AFF-NeRF: global shape and appearance codes from the input view(s)")
)
register_method(
    MethodSpec("pixelnerf", _build("pixelnerf"), "PixelNeRF-M: pixel-aligned features at the posed input views")
)
