"""What every image-conditioned radiance field here shares: encode input views, condition a coarse and a fine
field on them, render rays. AFF-NeRF and the PixelNeRF baseline differ only in the encoding and conditioning."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import torch
from torch import nn

from affnerf.model.config import POINTS_PER_CHUNK, ModelConfig
from affnerf.model.field import ConditionalField, PointGeometry
from affnerf.model.raymarch import Condition, FieldRenderer, RayOutputs
from affnerf.rendering.grid import OccupancyGrid, build_grid
from affnerf.rendering.samplers import SurfaceGuide


class ConditionedNeRF(nn.Module, ABC):
    """Base of image-conditioned fields.

    Subclasses set ``self.renderer`` and implement :meth:`encode_views` and :meth:`condition`.
    """

    config: ModelConfig
    num_classes: int
    renderer: FieldRenderer
    #: Whether encoding needs the input views' poses (multi-view baselines) or only the images (AFF-NeRF).
    needs_input_pose: bool = True

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__()
        self.config = config
        self.num_classes = num_classes

    @property
    def coarse(self) -> ConditionalField:
        return self.renderer.coarse

    @property
    def fine(self) -> ConditionalField | None:
        return self.renderer.fine

    @abstractmethod
    def encode_views(self, images: torch.Tensor, intrinsics: torch.Tensor, poses: torch.Tensor) -> Any:
        """Encode B objects from V input views each.

        Args:
            images: (B, V, 3, S, S) object-centred crops in [0, 1].
            intrinsics: (B, V, 4) the crops' (fl_x, fl_y, cx, cy).
            poses: (B, V, 4, 4) the views' camera-to-world poses.
        """

    def auxiliary_losses(
        self, encoding: Any, input_depth: torch.Tensor | None = None, input_labels: torch.Tensor | None = None
    ) -> dict[str, torch.Tensor]:
        """Training losses the model adds to the rendering loss, by log name (each 0-d; none by default).

        Args:
            encoding: what :meth:`encode_views` returned for the step's input views.
            input_depth: (B, V, S, S) true z-depth of the input crops (m, 0 = no surface), when the data has it.
            input_labels: (B, V, S, S) true affordance ids of the input crops' pixels, when the data has them.
        """
        return {}

    @abstractmethod
    def condition(self, encoding: Any, ray_object: torch.Tensor) -> Condition:
        """The per-point conditioning of rays whose object indices (into ``encoding``) are ``ray_object``."""

    def render_rays(
        self,
        encoding: Any,
        ray_object: torch.Tensor,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        perturb: bool = False,
        generator: torch.Generator | None = None,
        guide: SurfaceGuide | None = None,
    ) -> tuple[RayOutputs, RayOutputs | None]:
        """Render rays of encoded objects; ``ray_object`` (R,) indexes the objects of ``encoding``; ``guide``
        (training only) draws a share of the fine samples around the rays' true surface
        (:meth:`FieldRenderer.render_rays`)."""
        return self.renderer.render_rays(
            self.condition(encoding, ray_object), origins, dirs, background, perturb, generator, guide
        )

    def render_rays_in_grid(
        self,
        encoding: Any,
        grid: OccupancyGrid,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        num: int = 32,
    ) -> RayOutputs:
        """Render rays of one encoded object with empty-space skipping (see
        :meth:`FieldRenderer.render_rays_in_grid`)."""
        obj = torch.zeros(len(origins), dtype=torch.long, device=origins.device)
        return self.renderer.render_rays_in_grid(self.condition(encoding, obj), grid, origins, dirs, background, num)

    def occupancy(self, encoding: Any, resolution: int = 64, threshold: float | None = None) -> OccupancyGrid:
        """The occupancy grid of one encoded object's density over the scene cube (evaluated once; see
        :mod:`affnerf.rendering.grid`); ``threshold`` defaults to the config's ``occupancy_density``."""
        density, _ = self.point_fields(encoding)
        level = self.config.occupancy_density if threshold is None else threshold
        device = next(self.parameters()).device
        return build_grid(
            density, self.config.scene_half_extent, resolution, level, chunk=POINTS_PER_CHUNK, device=device
        )

    def forward(
        self,
        images: torch.Tensor,
        intrinsics: torch.Tensor,
        poses: torch.Tensor,
        ray_object: torch.Tensor,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        perturb: bool = True,
        generator: torch.Generator | None = None,
    ) -> tuple[RayOutputs, RayOutputs | None]:
        """Encode the input views and render rays (one training forward pass)."""
        encoding = self.encode_views(images, intrinsics, poses)
        return self.render_rays(encoding, ray_object, origins, dirs, background, perturb, generator)

    def point_geometry(self, encoding: Any, point_object: torch.Tensor, points: torch.Tensor) -> list[PointGeometry]:
        """Density, affordance logits (and a signed-distance field's distance) of every field at points of several
        encoded objects (3D supervision).

        Args:
            encoding: what :meth:`encode_views` returned for B objects.
            point_object: (P,) index of each point's object in ``encoding``.
            points: (P, 3) canonical positions.

        Returns:
            One :class:`~affnerf.model.field.PointGeometry` ((P,) density, (P, C - 1) logits, (P,) distance or None)
            per field: the coarse one, then the fine one if any.
        """
        rays = torch.arange(len(points), device=points.device)
        trunk_in = self.condition(encoding, point_object)(points, rays)[0]
        fields = [self.coarse] if self.fine is None else [self.coarse, self.fine]
        return [f.supervised(points, trunk_in) for f in fields]

    def _point_condition(self, encoding: Any, index: int) -> Any:
        """A callable (N, 3) points -> (the field used for meshes, the points on the model's device, their
        conditioned trunk input) for object ``index``: the fine field when there is one."""
        field = self.renderer.fine_field()
        device = next(self.parameters()).device

        def cond(points: torch.Tensor) -> tuple[Any, torch.Tensor, torch.Tensor]:
            points = points.to(device)
            rays = torch.arange(len(points), device=device)
            obj = torch.full((len(points),), index, dtype=torch.long, device=device)
            return field, points, self.condition(encoding, obj)(points, rays)[0]

        return cond

    def point_fields(self, encoding: Any, index: int = 0) -> tuple[Any, Any]:
        """Density and affordance-class callables of object ``index`` at arbitrary (N, 3) points (the fine field
        when there is one), for mesh extraction. The points may live on any device (mesh extraction makes its grid
        on the CPU): they are moved to the model's, and the results stay there."""
        cond = self._point_condition(encoding, index)

        def density(points: torch.Tensor) -> torch.Tensor:
            field, points, trunk_in = cond(points)
            return field.density_only(points, trunk_in)

        def labels(points: torch.Tensor) -> torch.Tensor:
            field, points, trunk_in = cond(points)
            return field.geometry(points, trunk_in)[1].argmax(dim=-1) + 1  # object classes start at 1

        return density, labels

    def point_probabilities(self, encoding: Any, index: int = 0) -> Any:
        """A callable giving object ``index``'s (N, C - 1) probabilities over the object classes (softmax of the
        affordance logits, the fine field when there is one) at (N, 3) points: how sure the field is of a label
        (:func:`affnerf.predict.mesh.face_confidence`). Devices as :meth:`point_fields`."""
        cond = self._point_condition(encoding, index)

        def probabilities(points: torch.Tensor) -> torch.Tensor:
            field, points, trunk_in = cond(points)
            return torch.softmax(field.geometry(points, trunk_in)[1], dim=-1)

        return probabilities
