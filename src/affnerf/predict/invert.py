"""Test-time inversion: fit an object's codes to the image they were encoded from (analysis by synthesis).

The encoders give the codes in one forward pass; they are a guess, and nothing checks that the object they describe
looks like the photo. CodeNeRF (Jang and Agapito, 2021) and DeepSDF's auto-decoder close that gap at test time by
optimising the latent codes (and the unknown camera) so that the decoder renders the observed image. Here:

1. **Camera search** (:func:`search_cameras`): the input camera is unknown (AFF-NeRF takes unposed photos), but
   dataset and photo cameras look at the canonical origin from the upper hemisphere (conventions §1). Every camera
   of a grid over azimuth, elevation and distance is scored by how well the encoded object's silhouette, projected
   through the crop's intrinsics, overlaps the object's mask in the crop (IoU). The best few are then rendered and
   the one with the lowest photometric loss wins, so symmetric outlines (a screwdriver seen end-on either way) are
   told apart by colour.
2. **Code fitting** (:func:`fit_codes`): Adam on the shape and appearance codes and on the camera's angles and
   distance, minimising, over the crop's pixels rendered at a low resolution, colour MSE plus the binary
   cross-entropy of opacity against the mask; plus the cross-entropy of the affordance, on those pixels and at
   points inside the encoded object, against what the encoder's codes give there (the fit may move and recolour
   surfaces, not relabel parts: without it, a fit relabels thin parts); plus a prior that keeps the codes near the
   encoder's (squared distance relative to the codes' own size). The decoder's weights never change.

Everything happens in the crop the encoders saw: its intrinsics come from the image's (a dataset's
``transforms.json``, or a 60° field of view for a photo) and the crop window, so the fitted camera is a real
camera of the canonical frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from affnerf.data.crop import crop_intrinsics, crop_object, crop_window, resample_to_crop
from affnerf.data.dataset import ObjectData
from affnerf.model.affnerf import Codes
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import POINTS_PER_CHUNK
from affnerf.model.raymarch import RayOutputs
from affnerf.predict.viewpoint import camera_grid, camera_pose, project_silhouettes, silhouette_iou
from affnerf.rendering.rays import pixel_rays

#: Share of a pixel the object must cover to count in the camera search's mask (thin frames and blades cover
#: little of a low-resolution pixel).
SEARCH_COVERAGE = 0.2


@dataclass(frozen=True)
class InversionConfig:
    """Settings of test-time inversion.

    Attributes:
        steps: Adam steps of code fitting (0: no fitting, the encoder's codes are kept).
        lr: learning rate of the codes (relative to their root-mean-square size) and of the camera angles (rad).
        prior: weight of the code prior, mean squared change over the codes' mean square.
        mask_weight: weight of the opacity-against-mask cross-entropy beside the colour MSE.
        affordance_weight: weight of the cross-entropy of the rendered affordance against what the encoder's codes
            render at the same pixels (the fit may move the surface and change colours, not relabel parts).
        anchor_points: points of the encoded object (occupied cells of the camera search) whose affordance the fit
            keeps, with the same weight (0: none).
        resolution: side of the crop rendering that is fitted, pixels.
        rays: rays per step, drawn at random from the crop's pixels (0: all of them).
        fit_camera: also optimise the camera's azimuth, elevation and distance.
        azimuths: azimuths of the camera search, evenly spaced over the full turn.
        elevations_deg: elevations of the camera search.
        distances: camera distances of the camera search, metres.
        search_resolution: density samples per axis of the silhouette used by the search.
        finalists: best cameras by silhouette that are rendered to choose by colour.
        hypotheses: fits run from the best cameras, each from the encoder's codes; the one with the lowest final
            loss is kept (1: the best camera only).
        seed: random source of the rays' draw.
    """

    steps: int = 30
    lr: float = 0.03
    prior: float = 5.0
    mask_weight: float = 1.0
    affordance_weight: float = 3.0
    anchor_points: int = 2048
    resolution: int = 32
    rays: int = 512
    fit_camera: bool = True
    azimuths: int = 24
    elevations_deg: tuple[float, ...] = (15.0, 30.0, 45.0, 60.0, 75.0)
    distances: tuple[float, ...] = (0.5, 0.6, 0.7, 0.8, 0.9)
    search_resolution: int = 40
    finalists: int = 12
    hypotheses: int = 1
    seed: int = 0


@dataclass(frozen=True)
class CropTarget:
    """What an input view shows, in its crop.

    Attributes:
        rgb: (S, S, 3) float colours in [0, 1] (background outside the object).
        mask: (S, S) float in [0, 1], 1 on the object.
        intrinsics: (4,) fl_x, fl_y, cx, cy of the crop at side S.
    """

    rgb: np.ndarray
    mask: np.ndarray
    intrinsics: np.ndarray


def crop_target(
    rgb: np.ndarray, mask: np.ndarray, intrinsics: np.ndarray, size: int, background: tuple[float, float, float]
) -> CropTarget:
    """The encoder crop of an image (:func:`affnerf.data.crop.crop_object`) with its mask and intrinsics.

    Args:
        rgb: (H, W, 3) uint8 image.
        mask: (H, W) bool, True on the object.
        intrinsics: (4,) fl_x, fl_y, cx, cy of the image.
        size: the crop's side in pixels.
        background: RGB in [0, 1] the crop places the object on.
    """
    window = crop_window(mask)
    k = np.asarray(intrinsics, np.float64)
    crop_k = np.array(crop_intrinsics(k[0], k[1], k[2], k[3], window, size))
    crop = crop_object(rgb, mask, size, background).astype(np.float32) / 255.0
    crop_mask = resample_to_crop(mask.astype(np.float32), k, crop_k, size)
    return CropTarget(crop, crop_mask, crop_k)


def dataset_crop_target(obj: ObjectData, view: int, size: int) -> CropTarget:
    """The encoder crop of one dataset view, with its object mask and its intrinsics (never its pose)."""
    k = obj.record.intrinsics
    mask = obj.affordance(view) > 0
    return crop_target(obj.rgb(view), mask, np.array([k.fl_x, k.fl_y, k.cx, k.cy]), size, obj.record.background_color)


@dataclass(frozen=True)
class InversionResult:
    """Fitted codes, the camera found, and how the fit went.

    Attributes:
        codes: the fitted codes (the encoder's when ``steps`` is 0).
        camera: (azimuth rad, elevation rad, distance m) of the input view in the canonical frame.
        search_iou: silhouette IoU of the chosen camera before fitting.
        loss_start: fitting loss with the encoder's codes at the chosen camera.
        loss_end: fitting loss after the last step.
    """

    codes: Codes
    camera: tuple[float, float, float]
    search_iou: float
    loss_start: float
    loss_end: float

    def camera_to_world(self) -> np.ndarray:
        """(4, 4) camera-to-canonical pose of :attr:`camera` (OpenGL convention, conventions §1)."""
        return camera_pose(*(torch.tensor(float(v), dtype=torch.float64) for v in self.camera)).numpy()


def _resize_mask(mask: np.ndarray, size: int) -> np.ndarray:
    """An (S, S) float mask area-averaged to (size, size): the object's coverage of each pixel, in [0, 1]."""
    t = torch.from_numpy(np.ascontiguousarray(mask, np.float32))[None, None]
    return F.interpolate(t, size=(size, size), mode="area")[0, 0].numpy()


@torch.no_grad()
def object_points(model: ConditionedNeRF, codes: Codes, resolution: int, level: float) -> np.ndarray:
    """(P, 3) centres of the cells of a ``resolution``^3 grid over the scene cube where the encoded object's
    density exceeds ``level``. (Not :func:`affnerf.rendering.grid.build_grid`, whose cell centres differ in the
    last float bits: the fit amplifies that into other figures than the committed ones.)"""
    h = model.config.scene_half_extent
    axis = (torch.arange(resolution, dtype=torch.float32) + 0.5) / resolution * 2 * h - h
    pts = torch.stack(torch.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    density, _ = model.point_fields(codes)
    values = torch.cat([density(chunk).cpu() for chunk in pts.split(POINTS_PER_CHUNK)])
    return pts[values > level].numpy().astype(np.float64)


def _pixels(size: int) -> torch.Tensor:
    vv, uu = torch.meshgrid(torch.arange(size), torch.arange(size), indexing="ij")
    return torch.stack([uu.reshape(-1), vv.reshape(-1)], 1)


def render_crop(
    model: ConditionedNeRF,
    codes: Codes,
    camera: torch.Tensor,
    pixels: torch.Tensor,
    intrinsics: torch.Tensor,
    background: torch.Tensor,
) -> list[RayOutputs]:
    """Render crop pixels of the encoded object from a camera (differentiable in the codes and the camera).

    Args:
        camera: (3,) azimuth, elevation, distance.
        pixels: (R, 2) crop pixel indices.
        intrinsics: (4,) the crop's intrinsics.
        background: (3,) background colour.

    Returns:
        The stages' outputs (coarse, then fine if the model has one).
    """
    pose = camera_pose(camera[0], camera[1], camera[2]).to(intrinsics.dtype)
    origins, dirs = pixel_rays(pixels, intrinsics, pose)
    obj = torch.zeros(len(pixels), dtype=torch.long, device=pixels.device)
    stages = model.render_rays(codes, obj, origins.float(), dirs.float(), background.expand(len(pixels), 3))
    return [s for s in stages if s is not None]


def crop_loss(
    stages: list[RayOutputs],
    rgb: torch.Tensor,
    mask: torch.Tensor,
    mask_weight: float,
    reference: list[torch.Tensor] | None = None,
    affordance_weight: float = 0.0,
) -> torch.Tensor:
    """0-d fitting loss summed over stages: colour MSE, ``mask_weight`` times the opacity's binary cross-entropy
    against the (R,) mask, and ``affordance_weight`` times the cross-entropy of each stage's (R, C) affordance
    against ``reference`` (the encoder's own prediction: the fit may move the surface, not relabel it)."""
    loss = torch.zeros((), device=rgb.device)
    for i, out in enumerate(stages):
        opacity = out.opacity.clamp(1e-4, 1 - 1e-4)
        loss = loss + F.mse_loss(out.rgb, rgb) + mask_weight * F.binary_cross_entropy(opacity, mask)
        if reference is not None and affordance_weight > 0:
            log_p = out.affordance.clamp_min(1e-6).log()
            loss = loss - affordance_weight * (reference[i] * log_p).sum(-1).mean()
    return loss


def target_tensors(
    target: CropTarget, size: int, device: torch.device
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """The crop resampled to ``size``: pixels (S*S, 2), colours (S*S, 3), mask (S*S,), intrinsics (4,), on
    ``device``."""
    s0 = target.rgb.shape[0]
    rgb = torch.from_numpy(np.ascontiguousarray(target.rgb, np.float32)).permute(2, 0, 1)[None]
    rgb = F.interpolate(rgb, size=(size, size), mode="area")[0].permute(1, 2, 0).reshape(-1, 3)
    mask = torch.from_numpy(_resize_mask(target.mask, size)).reshape(-1)
    k = torch.as_tensor(np.asarray(target.intrinsics, np.float64) * size / s0, dtype=torch.float64)
    return _pixels(size).to(device), rgb.to(device), mask.to(device), k.to(device)


def search_cameras(
    model: ConditionedNeRF,
    codes: Codes,
    points: np.ndarray,
    target: CropTarget,
    background: np.ndarray,
    config: InversionConfig,
) -> list[tuple[np.ndarray, float]]:
    """Candidate cameras of the input view: the ``finalists`` best by silhouette IoU of ``points`` (P, 3), the
    encoded object's occupied cells (:func:`object_points`), re-ranked by photometric loss.

    Returns:
        (camera, silhouette IoU) pairs, the lowest photometric loss first; a camera is (3,) azimuth, elevation,
        distance. One pair (the grid's first camera, IoU 0) when the object has no occupied cell.
    """
    size = config.resolution
    cameras = camera_grid(config.azimuths, config.elevations_deg, config.distances)
    device = next(model.parameters()).device
    pixels, rgb, mask, k = target_tensors(target, size, device)
    if len(points) == 0:
        return [(cameras[0], 0.0)]
    covered = mask.cpu().numpy().reshape(size, size) > SEARCH_COVERAGE
    iou = silhouette_iou(project_silhouettes(points, cameras, k.cpu().numpy(), size), covered)
    best = np.argsort(-iou, kind="stable")[: max(1, config.finalists)]
    bg = torch.as_tensor(np.asarray(background), dtype=torch.float32, device=device)
    with torch.no_grad():
        losses = []
        for i in best:
            stages = render_crop(model, codes, torch.from_numpy(cameras[i]).to(device), pixels, k, bg)
            losses.append(float(crop_loss(stages, rgb, mask, 1.0)))
    return [(cameras[best[j]], float(iou[best[j]])) for j in np.argsort(losses, kind="stable")]


def point_labels(model: ConditionedNeRF, codes: Codes, points: torch.Tensor) -> torch.Tensor:
    """(P, C - 1) object-class logits of the encoded object at (P, 3) points (the fine field when there is one)."""
    obj = torch.zeros(len(points), dtype=torch.long, device=points.device)
    return model.point_geometry(codes, obj, points)[-1].logits


def draw_rays(n: int, count: int, generator: torch.Generator) -> torch.Tensor:
    """(min(n, count),) distinct ray indices drawn at random from n (all n, in order, when ``count`` is 0 or at least
    n)."""
    if count <= 0 or count >= n:
        return torch.arange(n)
    return torch.randperm(n, generator=generator)[:count]


def fit_codes(
    model: ConditionedNeRF,
    codes: Codes,
    target: CropTarget,
    camera: np.ndarray,
    background: np.ndarray,
    config: InversionConfig,
    anchors: np.ndarray | None = None,
) -> tuple[Codes, np.ndarray, float, float]:
    """Adam on the codes (and the camera) against the crop; the model's weights are left untouched.

    ``anchors`` (P, 3), points of the encoded object, keep their affordance: the cross-entropy of the fitted
    codes' labels there against the encoder's codes' is added with ``affordance_weight`` (as on rendered pixels).

    Returns:
        the fitted codes (detached), the fitted camera (3,), the photometric loss (colour and mask) before the
        first and after the last step over every crop pixel.
    """
    device = next(model.parameters()).device
    pixels, rgb, mask, k = target_tensors(target, config.resolution, device)
    n = len(pixels)
    bg = torch.as_tensor(np.asarray(background), dtype=torch.float32, device=device)
    start = [codes.shape.detach(), codes.appearance.detach()]
    scales = [float(c.pow(2).mean().sqrt().clamp_min(1e-6)) for c in start]
    deltas = [torch.zeros_like(c, requires_grad=True) for c in start]  # in units of each code's size
    cam = torch.tensor(np.asarray(camera), dtype=torch.float32, device=device, requires_grad=config.fit_camera)
    optim = torch.optim.Adam(deltas + ([cam] if config.fit_camera else []), lr=config.lr)
    generator = torch.Generator().manual_seed(config.seed)

    def fitted() -> Codes:
        return Codes(start[0] + deltas[0] * scales[0], start[1] + deltas[1] * scales[1])

    with torch.no_grad():
        stages = render_crop(model, codes, cam, pixels, k, bg)
        reference = [s.affordance.detach() for s in stages]
        loss_start = float(crop_loss(stages, rgb, mask, config.mask_weight))
        anchor_t = None if anchors is None or not len(anchors) else torch.from_numpy(anchors).float().to(device)
        anchor_ref = None if anchor_t is None else point_labels(model, codes, anchor_t).softmax(-1)
    for _ in range(config.steps):
        pick = draw_rays(n, config.rays, generator).to(device)
        stages = render_crop(model, fitted(), cam, pixels[pick], k, bg)
        ref = [r[pick] for r in reference]
        loss = crop_loss(stages, rgb[pick], mask[pick], config.mask_weight, ref, config.affordance_weight)
        loss = loss + config.prior * sum(d.pow(2).mean() for d in deltas)
        if anchor_ref is not None and config.affordance_weight > 0:
            log_p = point_labels(model, fitted(), anchor_t).log_softmax(-1)
            loss = loss - config.affordance_weight * (anchor_ref * log_p).sum(-1).mean()
        optim.zero_grad(set_to_none=True)
        loss.backward()
        optim.step()
    with torch.no_grad():
        final = fitted()
        loss_end = float(crop_loss(render_crop(model, final, cam, pixels, k, bg), rgb, mask, config.mask_weight))
    fitted_camera = cam.detach().double().cpu().numpy()
    return Codes(final.shape.detach(), final.appearance.detach()), fitted_camera, loss_start, loss_end


def invert(
    model: ConditionedNeRF, codes: Codes, target: CropTarget, background: np.ndarray, config: InversionConfig
) -> InversionResult:
    """Search the input camera, then fit the codes to the crop (see the module docstring); with
    ``config.hypotheses`` > 1, fit from that many of the best cameras and keep the fit with the lowest loss."""
    trainable = [p.requires_grad for p in model.parameters()]
    for p in model.parameters():
        p.requires_grad_(False)
    try:
        points = object_points(model, codes, config.search_resolution, model.config.occupancy_density)
        candidates = search_cameras(model, codes, points, target, background, config)
        if config.steps <= 0:
            camera, iou = candidates[0]
            return InversionResult(codes, tuple(float(c) for c in camera), iou, math.nan, math.nan)
        rng = np.random.default_rng(config.seed)
        anchors = points[rng.permutation(len(points))[: config.anchor_points]] if config.anchor_points else None
        results = []
        for camera, iou in candidates[: max(1, config.hypotheses)]:
            fitted, camera, before, after = fit_codes(model, codes, target, camera, background, config, anchors)
            results.append(InversionResult(fitted, tuple(float(c) for c in camera), iou, before, after))
    finally:
        for p, flag in zip(model.parameters(), trainable, strict=True):
            p.requires_grad_(flag)
    return min(results, key=lambda r: r.loss_end)
