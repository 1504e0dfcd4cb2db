"""Input views of a dataset object, prepared as the models take them: crops, their intrinsics, poses."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

from affnerf.data.crop import crop_intrinsics, crop_object, crop_window
from affnerf.data.dataset import ObjectData
from affnerf.model.config import ModelConfig


def dataset_views(
    obj: ObjectData, views: Sequence[int], config: ModelConfig
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Encoder inputs of some views of one object, as the model of ``config`` takes them (its
    ``encoder_resolution`` and ``crop_outside``).

    Returns:
        images (1, V, 3, S, S) in [0, 1], crop intrinsics (1, V, 4) and camera-to-world poses (1, V, 4, 4).
    """
    k, size = obj.record.intrinsics, config.encoder_resolution
    crops, intr, poses = [], [], []
    for view in views:
        rgb, mask = obj.rgb(view), obj.affordance(view) > 0
        crops.append(crop_object(rgb, mask, size, obj.record.background_color, outside=config.crop_outside))
        intr.append(crop_intrinsics(k.fl_x, k.fl_y, k.cx, k.cy, crop_window(mask), size))
        poses.append(obj.pose(view))
    images = torch.from_numpy(np.stack(crops)).permute(0, 3, 1, 2).float()[None] / 255.0
    return images, torch.tensor([intr], dtype=torch.float32), torch.from_numpy(np.stack(poses)).float()[None]
