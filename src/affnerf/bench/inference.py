"""Inference latency: image -> codes, -> one 400x300 view, -> 20 views, -> mesh at 128^3; reference against fast.

The reference renders coarse-to-fine over the whole [near, far] range and evaluates the density on the whole
mesh grid; the fast path builds the object's occupancy grid once and samples and evaluates only in occupied
cells. The fast path's images are compared with the model's own coarse-to-fine rendering inside the cube (the
way it was trained), so the ratio is bought without a change of output.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from affnerf.bench.timing import timed
from affnerf.data.cameras import DEFAULT_CAMERA_ANGLE_X, Intrinsics
from affnerf.metrics.image import psnr
from affnerf.model.config import POINTS_PER_CHUNK, RAYS_PER_CHUNK
from affnerf.predict.loading import LoadedModel
from affnerf.predict.predictor import EncodedObject, Predictor, turntable_poses


def _reference(loaded: LoadedModel, chunk: int) -> Predictor:
    """The same model rendering like vanilla NeRF (full range, coarse then fine), without the grid."""
    model = loaded.model
    vanilla = replace(model.config, clip_to_cube=False)
    clone = type(model)(vanilla, model.num_classes).to(loaded.device)
    clone.load_state_dict(model.state_dict())
    clone.eval()
    return Predictor(replace(loaded, model=clone), chunk, fast=False)


def measure_inference(
    loaded: LoadedModel,
    crop: np.ndarray,
    repeats: int,
    views: int = 20,
    size: tuple[int, int] = (400, 300),
    resolution: int = 128,
    chunk: int | None = None,
) -> dict[str, Any]:
    """Latencies (seconds, median/min/max) of the fast and the reference path, and their ratios.

    Args:
        loaded: a trained model.
        crop: (S, S, 3) uint8 encoder crop of a test image.
        repeats: repeats of each measurement.
        views: views of the multi-view measurement.
        size: (width, height) of rendered views.
        resolution: marching-cubes grid resolution.
        chunk: rays per forward pass (default: RAYS_PER_CHUNK on CPU, POINTS_PER_CHUNK on GPU).
    """
    device = loaded.device
    chunk = chunk or (POINTS_PER_CHUNK if device.type == "cuda" else RAYS_PER_CHUNK)
    fast = Predictor(loaded, chunk, fast=True)
    reference = _reference(loaded, chunk)
    out: dict[str, Any] = {"size": list(size), "views": views, "mesh_resolution": resolution, "chunk": chunk}
    out["image_to_codes"] = timed(lambda: fast.encode_crops(crop[None]), repeats, device=device)
    intr = Intrinsics.from_fov(size[0], size[1], DEFAULT_CAMERA_ANGLE_X)
    cube = Predictor(loaded, chunk, fast=False)
    out["image_to_view"] = _view_latency(fast, reference, cube, crop, intr, repeats)

    def fast_views() -> None:
        obj = EncodedObject(fast.encode_crops(crop[None]))
        for p in turntable_poses(views):
            fast.render(obj, intr, p)

    out["image_to_views"] = {"fast": timed(fast_views, max(1, repeats // 2), warmup=0, device=device)}
    out["image_to_mesh"] = _mesh_latency(fast, reference, crop, resolution, repeats)
    return out


def _fast_vs_reference(fast: Any, reference: Any, repeats: int, device: Any) -> dict[str, Any]:
    """Timings of two callables (the reference repeated half as often, without warm-up) and the speed-up."""
    out = {
        "fast": timed(fast, repeats, device=device),
        "reference": timed(reference, max(1, repeats // 2), warmup=0, device=device),
    }
    out["speedup"] = out["reference"]["median"] / out["fast"]["median"]
    return out


def _view_latency(
    fast: Predictor, reference: Predictor, cube: Predictor, crop: np.ndarray, intr: Intrinsics, repeats: int
) -> dict[str, Any]:
    """Image -> one view, fast vs reference, and how closely the fast view matches the coarse-to-fine one."""
    pose = turntable_poses(8)[1]

    def view(predictor: Predictor) -> Any:
        return predictor.render(EncodedObject(predictor.encode_crops(crop[None])), intr, pose)

    out = _fast_vs_reference(lambda: view(fast), lambda: view(reference), repeats, fast.loaded.device)
    a, b = view(fast), view(cube)
    out["fast_vs_coarse_to_fine_psnr"] = psnr(a.rgb, b.rgb)
    out["label_agreement"] = float((a.labels == b.labels).mean())
    return out


def _mesh_latency(
    fast: Predictor, reference: Predictor, crop: np.ndarray, resolution: int, repeats: int
) -> dict[str, Any]:
    """Image -> labelled mesh, fast vs reference, and the faces each gives."""

    def mesh(predictor: Predictor) -> Any:
        return predictor.mesh(EncodedObject(predictor.encode_crops(crop[None])), resolution)

    out = _fast_vs_reference(lambda: mesh(fast), lambda: mesh(reference), repeats, fast.loaded.device)
    out["faces"] = {"fast": int(len(mesh(fast).faces)), "reference": int(len(mesh(reference).faces))}
    return out
