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
import torch

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
    loaded: LoadedModel, crop: np.ndarray, repeats: int, views: int = 20, size: tuple[int, int] = (400, 300),
    resolution: int = 128, chunk: int | None = None,
) -> dict[str, Any]:  # fmt: skip
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
    cube = Predictor(loaded, chunk, fast=False)
    reference = _reference(loaded, chunk)
    intr = Intrinsics.from_fov(size[0], size[1], DEFAULT_CAMERA_ANGLE_X)
    pose = turntable_poses(8)[1]
    codes = fast.encode_crops(crop[None])
    out: dict[str, Any] = {"size": list(size), "views": views, "mesh_resolution": resolution, "chunk": chunk}
    out["image_to_codes"] = timed(lambda: fast.encode_crops(crop[None]), repeats, device=device)

    def fast_view() -> Any:
        obj = EncodedObject(fast.encode_crops(crop[None]))
        return fast.render(obj, intr, pose)

    def reference_view() -> Any:
        return reference.render(EncodedObject(reference.encode_crops(crop[None])), intr, pose)

    out["image_to_view"] = {"fast": timed(fast_view, repeats, device=device),
                            "reference": timed(reference_view, max(1, repeats // 2), warmup=0, device=device)}  # fmt: skip
    out["image_to_view"]["speedup"] = out["image_to_view"]["reference"]["median"] / out["image_to_view"]["fast"]["median"]
    a = fast_view()
    b = cube.render(EncodedObject(cube.encode_crops(crop[None])), intr, pose)
    out["image_to_view"]["fast_vs_coarse_to_fine_psnr"] = psnr(a.rgb, b.rgb)
    out["image_to_view"]["label_agreement"] = float((a.labels == b.labels).mean())

    def fast_views() -> None:
        obj = EncodedObject(fast.encode_crops(crop[None]))
        for p in turntable_poses(views):
            fast.render(obj, intr, p)

    out["image_to_views"] = {"fast": timed(fast_views, max(1, repeats // 2), warmup=0, device=device)}

    def fast_mesh() -> Any:
        return fast.mesh(EncodedObject(fast.encode_crops(crop[None])), resolution)

    def reference_mesh() -> Any:
        return reference.mesh(EncodedObject(reference.encode_crops(crop[None])), resolution)

    out["image_to_mesh"] = {"fast": timed(fast_mesh, repeats, device=device),
                            "reference": timed(reference_mesh, max(1, repeats // 2), warmup=0, device=device)}  # fmt: skip
    out["image_to_mesh"]["speedup"] = out["image_to_mesh"]["reference"]["median"] / out["image_to_mesh"]["fast"]["median"]
    m_fast, m_ref = fast_mesh(), reference_mesh()
    out["image_to_mesh"]["faces"] = {"fast": int(len(m_fast.faces)), "reference": int(len(m_ref.faces))}
    del codes
    return out
