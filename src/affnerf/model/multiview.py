"""What the multi-view baselines (Semantic-Ray, GSNeRF) share: source-view feature maps, every sample of a ray
projected into every posed source view, scaled dot-product attention, and rendering that hands the conditioning a
whole ray of samples at a time.

The base contract (:class:`~affnerf.model.base.ConditionedNeRF`) conditions points one at a time:
``condition(points (N, 3), rays (N,))``. Attention along a ray needs the ray's samples together, so these models
build a *block condition* ``(points (R, S, 3), rays (R,)) -> (trunk input (R, S, Dt), colour input (R, S, Dc))``
and render with :class:`RayBlockRenderer`, whose stage passes it the (R, S) block. Points that are not on a
rendered ray (3D supervision, occupancy grids, mesh extraction) are each conditioned as a one-sample ray: attention
over one sample returns that sample's own value, so the model stays one function of the point there.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import torch
from torch.nn import functional as F

from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import ModelConfig
from affnerf.model.field import ConditionalField
from affnerf.model.pixelnerf import project
from affnerf.model.raymarch import Condition, FieldRenderer, RayOutputs, scatter_rays
from affnerf.model.resnet import ResNet18
from affnerf.rendering.grid import OccupancyGrid, occupied_samples
from affnerf.rendering.rays import intersect_aabb
from affnerf.rendering.samplers import merge_samples, stratified_samples

#: Positions per ray checked against the occupancy grid (as :meth:`FieldRenderer.render_rays_in_grid`).
GRID_CANDIDATES = 128
#: (points (R, S, 3), rays (R,)) -> (trunk input (R, S, Dt), colour input (R, S, Dc)).
BlockCondition = Callable[[torch.Tensor, torch.Tensor], tuple[torch.Tensor, torch.Tensor]]
#: (origins (R, 3), dirs (R, 3), rays (R,), coarse samples (R, S), near (R,), far (R,), perturb, generator) ->
#: extra samples (R, F).
FineSampler = Callable[..., torch.Tensor]


@dataclass
class ViewEncoding:
    """Source views of B objects: feature maps, the crops themselves, and their cameras.

    Attributes:
        features: (B, V, C, h, w) feature maps covering the crops.
        images: (B, V, 3, S, S) the crops in [0, 1] (colours to blend).
        intrinsics: (B, V, 4) crop intrinsics (fl_x, fl_y, cx, cy), pixels of the S x S crop.
        world_to_camera: (B, V, 4, 4).
        size: the crop side S.
    """

    features: torch.Tensor
    images: torch.Tensor
    intrinsics: torch.Tensor
    world_to_camera: torch.Tensor
    size: int


def stacked_features(backbone: ResNet18, images: torch.Tensor) -> torch.Tensor:
    """(N, 3, S, S) crops -> (N, C, S/4, S/4): the backbone's stages upsampled to the first and stacked (as
    PixelNeRF's feature pyramid)."""
    stages = backbone(images)
    size = stages[0].shape[-2:]
    ups = [F.interpolate(s, size=size, mode="bilinear", align_corners=False) for s in stages[1:]]
    return torch.cat([stages[0], *ups], dim=1)


def sample_views(
    points: torch.Tensor, maps: torch.Tensor, w2c: torch.Tensor, intrinsics: torch.Tensor, size: int
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Project (N, 3) world points into V posed views and read their maps there (bilinear).

    Args:
        points: (N, 3) canonical positions.
        maps: (V, C, h, w) maps covering each view's S x S crop (any resolution).
        w2c: (V, 4, 4) world-to-camera poses; intrinsics: (V, 4) crop intrinsics in crop pixels.
        size: the crop side S.

    Returns:
        (N, V, C) sampled values, (N, V, 3) the points in each camera's frame, (N, V) whether the point is in front
        of the camera and projects inside the crop.
    """
    values, cams, valid = [], [], []
    for v in range(maps.shape[0]):
        cam, pix = project(points, w2c[v], intrinsics[v])
        grid = (pix / size * 2.0 - 1.0)[None, :, None, :]
        feat = F.grid_sample(maps[v][None], grid, mode="bilinear", padding_mode="border", align_corners=False)
        values.append(feat[0, :, :, 0].T)
        cams.append(cam)
        inside = (pix >= 0).all(-1) & (pix <= size).all(-1)
        valid.append(inside & (cam[:, 2] < 0))
    return torch.stack(values, 1), torch.stack(cams, 1), torch.stack(valid, 1)


def attend(
    q: torch.Tensor, k: torch.Tensor, v: torch.Tensor, mask: torch.Tensor | None = None
) -> tuple[torch.Tensor, torch.Tensor]:
    """Scaled dot-product attention: softmax(q k^T / sqrt(D)) v over the keys a mask allows.

    Args:
        q: (..., Lq, D) queries; k: (..., L, D) keys; v: (..., L, E) values.
        mask: (..., L) keys that may be attended to; a query whose keys are all masked attends to all of them
            (a point no view sees still gets a value).

    Returns:
        (..., Lq, E) outputs and (..., Lq, L) attention weights.

    Example:
        >>> out, w = attend(torch.zeros(1, 2), torch.zeros(2, 2), torch.tensor([[1.0], [3.0]]))
        >>> out.tolist(), w.tolist()
        ([[2.0]], [[0.5, 0.5]])
    """
    scores = q @ k.transpose(-1, -2) / q.shape[-1] ** 0.5
    if mask is not None:
        keep = mask | ~mask.any(-1, keepdim=True)
        scores = scores.masked_fill(~keep[..., None, :], float("-inf"))
    weights = torch.softmax(scores, dim=-1)
    return weights @ v, weights


def masked_mean(x: torch.Tensor, mask: torch.Tensor, dim: int) -> torch.Tensor:
    """Mean of (..., L, ..., D) over the entries of ``dim`` that (..., L, ...) ``mask`` keeps (all when none is)."""
    keep = (mask | ~mask.any(dim, keepdim=True)).to(x.dtype)[..., None]
    return (x * keep).sum(dim) / keep.sum(dim)


def depth_band_samples(
    t_star: torch.Tensor,
    near: torch.Tensor,
    far: torch.Tensor,
    band: float,
    num: int,
    perturb: bool = False,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """(R, num) stratified samples in [t* - band, t* + band] clipped to each ray's [near, far] (depth-guided
    sampling); (R,) ``t_star`` is each ray's predicted depth."""
    lo = torch.maximum(near, torch.minimum(t_star - band, far))
    hi = torch.minimum(far, torch.maximum(t_star + band, near))
    return stratified_samples(lo, torch.maximum(hi, lo), num, perturb, generator)


class RayBlockRenderer(FieldRenderer):
    """A :class:`FieldRenderer` whose conditioning sees whole rays: every stage calls a :data:`BlockCondition`
    with its (R, S) samples, and the fine samples may come from a :data:`FineSampler` instead of the coarse
    weights (GSNeRF's depth-guided sampling)."""

    def _stage(
        self,
        field: ConditionalField,
        t: torch.Tensor,
        far: torch.Tensor,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        rays: torch.Tensor,
        condition: Condition,
        background: torch.Tensor,
        deltas: torch.Tensor | None = None,
    ) -> RayOutputs:
        r, s = t.shape

        def flat(points: torch.Tensor, ray_of_point: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            trunk, color = condition(points.reshape(r, s, 3), rays)
            return trunk.reshape(r * s, trunk.shape[-1]), color.reshape(r * s, color.shape[-1])

        return super()._stage(field, t, far, origins, dirs, rays, flat, background, deltas)

    def render_rays(
        self,
        condition: Condition,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        perturb: bool = False,
        generator: torch.Generator | None = None,
        fine_sampler: FineSampler | None = None,
    ) -> tuple[RayOutputs, RayOutputs | None]:
        """As :meth:`FieldRenderer.render_rays` with a block ``condition``; with ``fine_sampler``, the fine samples
        are its samples merged with the coarse ones (the fine field sees both)."""
        if fine_sampler is None or self.config.num_fine == 0:
            return super().render_rays(condition, origins, dirs, background, perturb, generator)
        near, far, hit = self.ray_bounds(origins, dirs)
        idx = torch.nonzero(hit, as_tuple=True)[0]
        o, d, bg, n_, f_ = origins[idx], dirs[idx], background[idx], near[idx], far[idx]
        t_coarse = stratified_samples(n_, f_, self.config.num_coarse, perturb, generator)
        with self.coarse_gradients():
            coarse = self._stage(self.coarse, t_coarse, f_, o, d, idx, condition, bg)
        t_fine = merge_samples(t_coarse, fine_sampler(o, d, idx, t_coarse, n_, f_, perturb, generator))
        fine = self._stage(self.fine_field(), t_fine, f_, o, d, idx, condition, bg)
        return scatter_rays(coarse, hit, background), scatter_rays(fine, hit, background)


class MultiViewNeRF(ConditionedNeRF):
    """Base of the models whose conditioning attends along rays: each source view goes through ``self.backbone``
    (a ResNet18 of ``encoder_width``, three stages); subclasses set ``self.renderer`` to a
    :class:`RayBlockRenderer` and implement :meth:`encode_views` and :meth:`ray_condition`."""

    renderer: RayBlockRenderer

    def __init__(self, config: ModelConfig, num_classes: int) -> None:
        super().__init__(config, num_classes)
        self.backbone = ResNet18(config.encoder_width, stages=3)

    @abstractmethod
    def ray_condition(self, encoding: Any, ray_object: torch.Tensor) -> BlockCondition:
        """The block conditioning of rays whose object indices (into ``encoding``) are ``ray_object``."""

    def fine_sampler(self, encoding: Any, ray_object: torch.Tensor) -> FineSampler | None:
        """Where the fine samples go; None: inverse-CDF sampling of the coarse weights (NeRF's)."""
        return None

    def condition(self, encoding: Any, ray_object: torch.Tensor) -> Condition:
        """Per-point conditioning (the base contract): each point is a one-sample ray."""
        block = self.ray_condition(encoding, ray_object)

        def cond(points: torch.Tensor, rays: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            trunk, color = block(points[:, None, :], rays)
            return trunk[:, 0], color[:, 0]

        return cond

    def render_rays(
        self,
        encoding: Any,
        ray_object: torch.Tensor,
        origins: torch.Tensor,
        dirs: torch.Tensor,
        background: torch.Tensor,
        perturb: bool = False,
        generator: torch.Generator | None = None,
    ) -> tuple[RayOutputs, RayOutputs | None]:
        """Render rays of encoded objects, each ray's samples conditioned together."""
        return self.renderer.render_rays(
            self.ray_condition(encoding, ray_object),
            origins,
            dirs,
            background,
            perturb,
            generator,
            self.fine_sampler(encoding, ray_object),
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
        """The fast path of attention models: rays that cross no occupied cell of ``grid`` render background
        without evaluating the field; the others are rendered as in training (coarse, then fine samples), since
        attention along a ray depends on where its samples are (``num`` is not used)."""
        c = self.config
        near, far, inside = intersect_aabb(origins, dirs, grid.half_extent, c.near, c.far)
        _, _, crosses = occupied_samples(grid, origins, dirs, near, far, 1, GRID_CANDIDATES)
        hit = crosses & inside
        idx = torch.nonzero(hit, as_tuple=True)[0]
        obj = torch.zeros(len(idx), dtype=torch.long, device=origins.device)
        coarse, fine = self.render_rays(encoding, obj, origins[idx], dirs[idx], background[idx])
        return scatter_rays(fine if fine is not None else coarse, hit, background)


def per_object(
    ray_object: torch.Tensor, rays: torch.Tensor, points: torch.Tensor, width: tuple[int, int], fn: Callable
) -> tuple[torch.Tensor, torch.Tensor]:
    """Apply ``fn(b, points (r, S, 3)) -> (trunk (r, S, Dt), colour (r, S, Dc))`` to each object's rays of a
    block ``points`` (R, S, 3) and assemble (R, S, Dt), (R, S, Dc); ``width`` is (Dt, Dc)."""
    obj = ray_object[rays]
    r, s = points.shape[:2]
    trunk = points.new_zeros(r, s, width[0])
    color = points.new_zeros(r, s, width[1])
    for b in torch.unique(obj).tolist():
        sel = obj == b
        trunk[sel], color[sel] = fn(b, points[sel])
    return trunk, color
