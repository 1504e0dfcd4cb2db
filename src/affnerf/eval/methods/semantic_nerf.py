"""Semantic-NeRF per object: a radiance field with a semantic (affordance) head fitted on the input views of one
object alone (Zhi et al. 2021), then rendered at the target cameras. With one input view it shows what a
single image gives without a learned prior; with many views it is a reference for what the views determine. Its
mesh for the 3D metrics is extracted from the field last fitted (no refitting).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch

from affnerf.data.dataset import ObjectData
from affnerf.eval.protocol import Prediction, TargetSet, resized
from affnerf.eval.registry import MethodContext, MethodSpec, register_method
from affnerf.meshio import LabelledMesh
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import RAYS_PER_CHUNK, ModelConfig
from affnerf.model.raymarch import Condition, FieldRenderer
from affnerf.model.views import render_view
from affnerf.predict.mesh import model_mesh
from affnerf.train.cache import frames_from_arrays
from affnerf.train.loss import nerf_loss
from affnerf.train.sampler import RaySampler


@dataclass(frozen=True)
class SemanticNeRFConfig:
    """Per-object fitting.

    Attributes:
        steps: optimisation steps per object.
        rays: rays per step.
        lr: Adam learning rate.
        affordance_weight: weight of the semantic cross-entropy (Semantic-NeRF's 4e-2).
        foreground_fraction: share of rays drawn on the object.
        model: field sizes and sampling (no encoders).
        seed: seed of initialisation and sampling.
    """

    steps: int = 400
    rays: int = 512
    lr: float = 2e-3
    affordance_weight: float = 4e-2
    foreground_fraction: float = 0.5
    model: ModelConfig = field(
        default_factory=lambda: ModelConfig(
            field_width=64,
            field_depth=4,
            color_width=32,
            affordance_width=32,
            num_coarse=32,
            num_fine=32,
            clip_to_cube=True,
        )
    )
    seed: int = 0


class ObjectNeRF(ConditionedNeRF):
    """An unconditioned field: one object, no encoder."""

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        self.renderer = FieldRenderer(config, num_classes, 0, 0)

    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> None:
        return None

    def condition(self, encoding: Any, ray_object: torch.Tensor) -> Condition:
        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            empty = points.new_zeros(len(points), 0)
            return empty, empty

        return cond


class SemanticNeRFMethod:
    """Fits an :class:`ObjectNeRF` on each object's input views (at the scored resolution); :meth:`mesh` extracts
    the last fitted field's mesh at ``mesh_resolution``."""

    def __init__(
        self,
        num_classes: int,
        config: SemanticNeRFConfig = SemanticNeRFConfig(),
        chunk: int = RAYS_PER_CHUNK,
        fast: bool = True,
        mesh_resolution: int = 128,
    ) -> None:
        self.num_classes, self.config, self.chunk, self.fast = num_classes, config, chunk, fast
        self.mesh_resolution = mesh_resolution
        self.name = "semantic-nerf"
        self._fitted: tuple[tuple[str, tuple[int, ...]], ObjectNeRF] | None = None

    def fit(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> ObjectNeRF:
        """Optimise a field on the input views of ``obj``."""
        c = self.config
        size = (targets.intrinsics.width, targets.intrinsics.height)
        k = targets.intrinsics
        frames = frames_from_arrays(
            obj.record.object_id,
            np.stack([resized(obj.rgb(i), size, nearest=False) for i in inputs]),
            np.stack([resized(obj.affordance(i), size, nearest=True) for i in inputs]),
            np.stack([obj.pose(i) for i in inputs]),
            np.array([k.fl_x, k.fl_y, k.cx, k.cy]),
            np.asarray(targets.background),
        )
        torch.manual_seed(c.seed)
        model = ObjectNeRF(c.model, self.num_classes)
        optimizer = torch.optim.Adam(model.parameters(), lr=c.lr)
        sampler = RaySampler([frames], 1, c.rays, c.foreground_fraction, c.seed, input_views=0)
        generator = torch.Generator().manual_seed(c.seed)
        for _ in range(c.steps):
            b = sampler.next_batch()
            coarse, fine = model.render_rays(None, b.ray_object, b.origins, b.dirs, b.background, True, generator)
            loss = nerf_loss(coarse, fine, b.rgb, b.labels, c.affordance_weight).total
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            optimizer.step()
        return model.eval()

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction:
        model = self.fit(obj, inputs, targets)
        self._fitted = ((obj.record.object_id, tuple(inputs)), model)
        with torch.no_grad():
            grid = model.occupancy(None) if self.fast else None
        views = [
            render_view(model, None, targets.intrinsics, p, targets.background, self.chunk, grid) for p in targets.poses
        ]
        return Prediction(np.stack([v.labels for v in views]), np.stack([v.rgb for v in views]))

    def mesh(self, obj: ObjectData, inputs: list[int]) -> LabelledMesh | None:
        """The labelled mesh of the field fitted by the last :meth:`predict` when it was of this object and these
        inputs (marching cubes at its ``surface_density``); None otherwise (fitting needs the target resolution)."""
        if self._fitted is None or self._fitted[0] != (obj.record.object_id, tuple(inputs)):
            return None
        model = self._fitted[1]
        with torch.no_grad():
            grid = model.occupancy(None)
        return model_mesh(model, None, self.mesh_resolution, level=None, occupancy=grid)


def _build(context: MethodContext) -> SemanticNeRFMethod:
    classes = len(context.dataset.affordance_classes)
    config = SemanticNeRFConfig(steps=context.semantic_steps)
    return SemanticNeRFMethod(classes, config, context.chunk, context.fast, context.mesh_resolution)


register_method(MethodSpec("semantic-nerf", _build, "Semantic-NeRF fitted per object on its input views"))
