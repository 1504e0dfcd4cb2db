"""Validation during training: encode one view of held-out objects, render others, score and picture them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from PIL import Image

from affnerf.data.dataset import ObjectData
from affnerf.metrics.image import psnr
from affnerf.metrics.segmentation import confusion_matrix, mean_iou, pixel_accuracy
from affnerf.model.base import ConditionedNeRF
from affnerf.model.config import RAYS_PER_CHUNK
from affnerf.model.inputs import dataset_views
from affnerf.model.views import render_view
from affnerf.pictures.compose import depth_to_color, overlay_affordance


@dataclass
class ValidationResult:
    """Scores over the rendered views and one picture per object.

    Attributes:
        psnr: mean PSNR of the RGB renders (dB).
        miou: affordance mIoU over all rendered pixels (classes present in the ground truth).
        accuracy: affordance pixel accuracy.
        images: (H, W, 3) uint8 strips: GT RGB | RGB | depth | GT affordance | affordance, one per object.
    """

    psnr: float
    miou: float
    accuracy: float
    images: list[np.ndarray]


def _downscale(image: np.ndarray, size: tuple[int, int], nearest: bool) -> np.ndarray:
    return np.asarray(Image.fromarray(image).resize(size, Image.NEAREST if nearest else Image.BOX))


@torch.no_grad()
def validate(
    model: ConditionedNeRF,
    objects: list[ObjectData],
    scale: float,
    views_per_object: int = 2,
    chunk: int = RAYS_PER_CHUNK,
    input_views: int = 1,
) -> ValidationResult:
    """Encode the first views of each object and render ``views_per_object`` others at ``scale`` of their size."""
    device = next(model.parameters()).device
    was_training = model.training
    model.eval()
    psnrs, images = [], []
    num_classes = model.num_classes
    conf = np.zeros((num_classes, num_classes), np.int64)
    try:
        for obj in objects:
            inputs = list(range(input_views))
            crops, intrinsics, poses = dataset_views(obj, inputs, model.config)
            encoding = model.encode_views(crops.to(device), intrinsics.to(device), poses.to(device))
            intr = obj.record.intrinsics.scaled(scale)
            size = (intr.width, intr.height)
            targets = np.linspace(input_views, len(obj) - 1, views_per_object).round().astype(int)
            for k, view in enumerate(targets):
                out = render_view(model, encoding, intr, obj.pose(int(view)), obj.record.background_color, chunk)
                gt_rgb = _downscale(obj.rgb(int(view)), size, nearest=False)
                gt_aff = _downscale(obj.affordance(int(view)), size, nearest=True)
                psnrs.append(psnr(out.rgb, gt_rgb / 255.0))
                conf += confusion_matrix(gt_aff, out.labels, num_classes)
                if k == 0:
                    rgb8 = np.round(out.rgb * 255).astype(np.uint8)
                    images.append(
                        np.concatenate(
                            [
                                gt_rgb,
                                rgb8,
                                depth_to_color(out.depth),
                                overlay_affordance(gt_rgb, gt_aff),
                                overlay_affordance(rgb8, out.labels),
                            ],
                            axis=1,
                        )
                    )
    finally:
        model.train(was_training)
    return ValidationResult(float(np.mean(psnrs)), mean_iou(conf), pixel_accuracy(conf), images)
