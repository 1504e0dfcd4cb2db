"""The evaluation protocol of conventions §5 (the paper's Table 2), for any method.

For each object: input views chosen by a fixed seed, K other views as targets. A method sees the input views
(images, poses, and for the per-object baselines their labels) and predicts RGB and affordance labels at the
target cameras. Per category one confusion matrix accumulates all its target views; metrics follow
:mod:`affnerf.metrics.segmentation`, PSNR is averaged over target views.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from PIL import Image

from affnerf.data.cameras import Intrinsics
from affnerf.data.dataset import ObjectData
from affnerf.metrics.image import psnr
from affnerf.metrics.segmentation import confusion_matrix, segmentation_metrics

METRIC_KEYS = ("mIoU", "PA", "MPA", "mIoU_object", "PA_object", "MPA_object", "PSNR")


@dataclass(frozen=True)
class ProtocolConfig:
    """How views are chosen and at what resolution they are scored.

    Attributes:
        input_views: views each method is given (1 for single-image methods).
        target_views: views scored per object (K).
        scale: resolution of the scored views as a fraction of the dataset's images.
        seed: seed of the view choice (the same for every method).
    """

    input_views: int = 1
    target_views: int = 20
    scale: float = 1.0
    seed: int = 0


def choose_views(num_frames: int, object_id: str, config: ProtocolConfig) -> tuple[list[int], list[int]]:
    """Input and target frame indices of an object: a seeded shuffle, inputs first, never overlapping.

    Example:
        >>> i, t = choose_views(10, "pen_0001", ProtocolConfig(input_views=1, target_views=3))
        >>> len(i), len(t), set(i) & set(t)
        (1, 3, set())
    """
    rng = np.random.default_rng([config.seed, zlib.crc32(object_id.encode())])
    order = rng.permutation(num_frames).tolist()
    inputs = order[: config.input_views]
    targets = order[config.input_views : config.input_views + config.target_views]
    return sorted(inputs), sorted(targets)


@dataclass
class TargetSet:
    """What a method must predict for one object: the target cameras, at the scored resolution."""

    intrinsics: Intrinsics
    poses: np.ndarray  # (K, 4, 4)
    background: tuple[float, float, float]


@dataclass
class Prediction:
    """A method's output at the target cameras: labels (K, H, W) uint8 and, if it renders colour, RGB
    (K, H, W, 3) float in [0, 1]."""

    labels: np.ndarray
    rgb: np.ndarray | None = None


class Method(Protocol):
    """Anything that predicts affordance (and maybe colour) at new cameras from some views of an object."""

    name: str

    def predict(self, obj: ObjectData, inputs: list[int], targets: TargetSet) -> Prediction: ...


def resized(image: np.ndarray, size: tuple[int, int], nearest: bool) -> np.ndarray:
    """An image resized to (width, height): area averaging for colour, nearest for labels."""
    if (image.shape[1], image.shape[0]) == size:
        return image
    return np.asarray(Image.fromarray(image).resize(size, Image.NEAREST if nearest else Image.BOX))


@dataclass
class CategoryResult:
    """Accumulated scores of one category."""

    confusion: np.ndarray
    psnr: list[float] = field(default_factory=list)
    objects: int = 0
    views: int = 0


@dataclass
class EvalResult:
    """Per-category accumulations of one method, and the pictures kept for the figure."""

    method: str
    split: str
    num_classes: int
    categories: dict[str, CategoryResult] = field(default_factory=dict)
    examples: list[dict[str, Any]] = field(default_factory=list)

    def add(self, category: str, gt: np.ndarray, pred: Prediction, gt_rgb: np.ndarray) -> None:
        """Add one object's target views: ground-truth labels (K, H, W) and RGB (K, H, W, 3) uint8."""
        cat = self.categories.setdefault(category, CategoryResult(np.zeros((self.num_classes,) * 2, np.int64)))
        cat.confusion += confusion_matrix(gt, pred.labels, self.num_classes)
        if pred.rgb is not None:
            cat.psnr += [psnr(p, g / 255.0) for p, g in zip(pred.rgb, gt_rgb, strict=True)]
        cat.objects += 1
        cat.views += len(gt)

    def to_json(self) -> dict[str, Any]:
        """The conventions §5 ``metrics.json`` schema: per category, and the mean over categories."""
        cats: dict[str, dict[str, Any]] = {}
        for name, c in sorted(self.categories.items()):
            m: dict[str, Any] = segmentation_metrics(c.confusion)
            m["PSNR"] = float(np.mean(c.psnr)) if c.psnr else None
            m.update(objects=c.objects, views=c.views)
            cats[name] = m
        mean: dict[str, Any] = {}
        for key in METRIC_KEYS:
            values = [m[key] for m in cats.values() if m[key] is not None and np.isfinite(m[key])]
            mean[key] = float(np.mean(values)) if values else None
        mean["objects"] = sum(m["objects"] for m in cats.values())
        mean["views"] = sum(m["views"] for m in cats.values())
        return {"categories": cats, "mean": mean, "method": self.method, "split": self.split}


def evaluate(
    method: Method,
    objects: Sequence[ObjectData],
    config: ProtocolConfig,
    split: str,
    num_classes: int,
    keep_examples: int = 0,
) -> EvalResult:
    """Run the protocol for one method over objects.

    Args:
        method: the method.
        objects: the objects to score.
        config: view choice and resolution.
        split: name recorded in the result.
        num_classes: affordance classes including background.
        keep_examples: keep this many objects' first target (input, ground truth, prediction) for figures.
    """
    result = EvalResult(method.name, split, num_classes)
    for obj in objects:
        inputs, targets = choose_views(len(obj), obj.record.object_id, config)
        intr = obj.record.intrinsics.scaled(config.scale)
        size = (intr.width, intr.height)
        target_set = TargetSet(intr, np.stack([obj.pose(i) for i in targets]), obj.record.background_color)
        pred = method.predict(obj, inputs, target_set)
        gt = np.stack([resized(obj.affordance(i), size, nearest=True) for i in targets])
        gt_rgb = np.stack([resized(obj.rgb(i), size, nearest=False) for i in targets])
        result.add(obj.record.category, gt, pred, gt_rgb)
        if len(result.examples) < keep_examples:
            result.examples.append(
                {
                    "object_id": obj.record.object_id,
                    "input": resized(obj.rgb(inputs[0]), size, nearest=False),
                    "gt_rgb": gt_rgb[0],
                    "gt_labels": gt[0],
                    "labels": pred.labels[0],
                    "rgb": None if pred.rgb is None else pred.rgb[0],
                }
            )
    return result
