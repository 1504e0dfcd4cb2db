"""Image-conditioned fields under the protocol (AFF-NeRF and the posed baselines PixelNeRF-M, Semantic-Ray,
GSNeRF): encode the input views, render the target cameras, and extract the labelled mesh of the encoding for the
3D metrics."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.data.dataset import ObjectData
from affnerf.errors import AffnerfError
from affnerf.eval.protocol import Prediction, TargetSet
from affnerf.eval.registry import MethodContext, MethodSpec, register_method
from affnerf.meshio import LabelledMesh
from affnerf.model.config import RAYS_PER_CHUNK
from affnerf.model.inputs import dataset_views
from affnerf.model.views import render_view
from affnerf.predict.loading import LoadedModel, load_model
from affnerf.predict.mesh import model_mesh
from affnerf.predict.predictor import pick_device
from affnerf.rendering.grid import OccupancyGrid


class ConditionedNeRFMethod:
    """A trained model of any kind; its name is the model's kind (``affnerf``, ``pixelnerf``, ``semantic-ray``,
    ``gsnerf``).

    Args:
        loaded: the model.
        chunk: rays per forward pass.
        fast: render with the object's occupancy grid (empty-space skipping).
        mesh_resolution: marching-cubes samples per axis of :meth:`mesh`.
    """

    def __init__(
        self, loaded: LoadedModel, chunk: int = RAYS_PER_CHUNK, fast: bool = True, mesh_resolution: int = 128
    ) -> None:
        self.loaded = loaded
        self.chunk = chunk
        self.fast = fast
        self.mesh_resolution = mesh_resolution
        self.name = loaded.model.config.kind
        self._key: tuple[str, tuple[int, ...]] | None = None
        self._encoding: object = None
        self._grid: OccupancyGrid | None = None

    @torch.no_grad()
    def encode(self, obj: ObjectData, inputs: list[int]):
        """The object's encoding from its input views (AFF-NeRF averages the views' codes)."""
        model = self.loaded.model
        device = self.loaded.device
        images, intr, poses = dataset_views(obj, inputs, model.config)
        return model.encode_views(images.to(device), intr.to(device), poses.to(device))

    def encoded(self, obj: ObjectData, inputs: list[int]) -> object:
        """The encoding of ``obj`` from ``inputs``, kept for the last object and inputs (so :meth:`predict` and
        :meth:`mesh` of the same inputs encode once)."""
        key = (obj.record.object_id, tuple(inputs))
        if self._key != key:
            self._key, self._encoding, self._grid = key, self.encode(obj, inputs), None
        return self._encoding

    @torch.no_grad()
    def occupancy(self, obj: ObjectData, inputs: list[int]) -> OccupancyGrid:
        """The occupancy grid of the encoding of ``obj`` from ``inputs`` (kept like the encoding)."""
        encoding = self.encoded(obj, inputs)
        if self._grid is None:
            self._grid = self.loaded.model.occupancy(encoding)
        return self._grid

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        encoding = self.encoded(obj, inputs)
        model = self.loaded.model
        grid = self.occupancy(obj, inputs) if self.fast else None
        views = [
            render_view(model, encoding, targets.intrinsics, pose, targets.background, self.chunk, grid)
            for pose in targets.poses
        ]
        return Prediction(np.stack([v.labels for v in views]), np.stack([v.rgb for v in views]))

    def mesh(self, obj: ObjectData, inputs: list[int]) -> LabelledMesh:
        """The labelled mesh of the encoding (marching cubes at the model's ``surface_density``; no faces when the
        field never reaches it)."""
        encoding, grid = self.encoded(obj, inputs), self.occupancy(obj, inputs)
        return model_mesh(self.loaded.model, encoding, self.mesh_resolution, level=None, occupancy=grid)


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
    return lambda context: ConditionedNeRFMethod(
        load_run(context, kind, kind), context.chunk, context.fast, context.mesh_resolution
    )


register_method(
    MethodSpec("affnerf", _build("affnerf"), "AFF-NeRF: global shape and appearance codes from the input view(s)")
)
register_method(
    MethodSpec("pixelnerf", _build("pixelnerf"), "PixelNeRF-M: pixel-aligned features at the posed input views")
)
register_method(
    MethodSpec(
        "pose-aware",
        _build("pose-aware"),
        "AFF-NeRF, pose-aware: global codes plus pixel-aligned features at the input camera it predicts",
    )
)
register_method(
    MethodSpec(
        "semantic-ray",
        _build("semantic-ray"),
        "Semantic-Ray: Cross-Reprojection Attention over the posed input views (baseline)",
    )
)
register_method(
    MethodSpec(
        "gsnerf", _build("gsnerf"), "GSNeRF: per-view depth from a cost volume, depth-guided rendering (baseline)"
    )
)
