"""The evaluation protocol of conventions §5 (the paper's Table 2), for any method.

For each object: input views chosen by a fixed seed, K other views as targets. A method sees the input views
(images, poses, and for the per-object baselines their labels) and predicts RGB and affordance labels at the
target cameras. Per category one confusion matrix accumulates all its target views; metrics follow
:mod:`affnerf.metrics.segmentation`, PSNR is averaged over target views. With ``metrics_3d`` a method's mesh (if it
gives one) is scored against the object's true mesh (:mod:`affnerf.eval.surface`); with ``stability_views`` N each
object is also predicted from N - 1 other input views and the spread of its scores reported
(:mod:`affnerf.eval.stability`).
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
from affnerf.eval.stability import StabilityRecord, input_sets, merge_stability, stability_json
from affnerf.eval.surface import (
    SurfaceScore,
    category_surface,
    mean_surface,
    method_mesh,
    sample_seed,
    score_mesh,
    true_samples,
)
from affnerf.metrics.image import psnr
from affnerf.metrics.segmentation import (
    confusion_matrix,
    iou_per_class,
    mean_iou,
    present_classes,
    segmentation_metrics,
)
from affnerf.metrics.surface import SurfaceSamples

METRIC_KEYS = ("mIoU", "PA", "MPA", "mIoU_object", "PA_object", "MPA_object", "PSNR")


@dataclass(frozen=True)
class ProtocolConfig:
    """How views are chosen and at what resolution they are scored.

    Attributes:
        input_views: views each method is given (1 for single-image methods).
        target_views: views scored per object (K).
        scale: resolution of the scored views as a fraction of the dataset's images.
        seed: seed of the view choice (the same for every method).
        metrics_3d: also score each method's mesh against the object's true mesh (methods without meshes get
            ``null``).
        stability_views: predict each object from this many input-view sets and report the spread of its scores
            (0 = off; the extra predictions are not part of the other metrics).
    """

    input_views: int = 1
    target_views: int = 20
    scale: float = 1.0
    seed: int = 0
    metrics_3d: bool = False
    stability_views: int = 0


def view_order(num_frames: int, object_id: str, seed: int) -> list[int]:
    """The object's frames in the seeded order the protocol takes inputs and targets from."""
    return np.random.default_rng([seed, zlib.crc32(object_id.encode())]).permutation(num_frames).tolist()


def choose_views(num_frames: int, object_id: str, config: ProtocolConfig) -> tuple[list[int], list[int]]:
    """Input and target frame indices of an object: a seeded shuffle, inputs first, never overlapping.

    Example:
        >>> i, t = choose_views(10, "pen_0001", ProtocolConfig(input_views=1, target_views=3))
        >>> len(i), len(t), set(i) & set(t)
        (1, 3, set())
    """
    order = view_order(num_frames, object_id, config.seed)
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
    """Anything that predicts affordance (and maybe colour) at new cameras from some views of an object.

    A method may also give meshes: ``mesh(obj, inputs) -> LabelledMesh | None`` (:class:`affnerf.eval.surface.
    MeshMethod`), scored by the 3D metrics.
    """

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
    surface: list[SurfaceScore | None] = field(default_factory=list)
    objects: int = 0
    views: int = 0


@dataclass
class EvalResult:
    """Per-category accumulations of one method, and the pictures kept for the figure.

    ``metrics_3d`` adds the 3D keys to every category (``null`` without meshes); ``stability_views`` > 0 adds the
    ``stability`` section built from ``stability``.
    """

    method: str
    split: str
    num_classes: int
    categories: dict[str, CategoryResult] = field(default_factory=dict)
    examples: list[dict[str, Any]] = field(default_factory=list)
    metrics_3d: bool = False
    stability_views: int = 0
    stability: list[StabilityRecord] = field(default_factory=list)

    def add(self, category: str, gt: np.ndarray, pred: Prediction, gt_rgb: np.ndarray) -> None:
        """Add one object's target views: ground-truth labels (K, H, W) and RGB (K, H, W, 3) uint8."""
        cat = self.categories.setdefault(category, CategoryResult(np.zeros((self.num_classes,) * 2, np.int64)))
        cat.confusion += confusion_matrix(gt, pred.labels, self.num_classes)
        if pred.rgb is not None:
            cat.psnr += [psnr(p, g / 255.0) for p, g in zip(pred.rgb, gt_rgb, strict=True)]
        cat.objects += 1
        cat.views += len(gt)

    def add_surface(self, category: str, score: SurfaceScore | None) -> None:
        """Add one object's 3D scores (None: the method gave no mesh), after :meth:`add` of its views."""
        self.categories[category].surface.append(score)

    def to_json(self) -> dict[str, Any]:
        """The conventions §5 ``metrics.json`` schema: per category, and the mean over categories."""
        cats: dict[str, dict[str, Any]] = {}
        for name, c in sorted(self.categories.items()):
            m: dict[str, Any] = segmentation_metrics(c.confusion)
            m.update(per_class_scores(c.confusion))
            m["PSNR"] = float(np.mean(c.psnr)) if c.psnr else None
            if self.metrics_3d:
                m.update(category_surface(c.surface))
            m.update(objects=c.objects, views=c.views)
            cats[name] = m
        out = {"categories": cats, "mean": category_mean(cats, self.metrics_3d), "method": self.method}
        out["split"] = self.split
        if self.stability_views:
            out["stability"] = stability_json(self.stability, self.stability_views)
        return out


def per_class_scores(conf: np.ndarray) -> dict[str, Any]:
    """``IoU_per_class``: (C,) IoU of each class present in the (C, C) ground-truth-by-prediction ``conf`` (None for
    the absent ones, which the means leave out), and ``confusion`` itself as nested lists, in vocabulary order."""
    iou = iou_per_class(conf)
    present = set(present_classes(conf).tolist())
    per_class = [float(v) if k in present else None for k, v in enumerate(iou)]
    return {"IoU_per_class": per_class, "confusion": conf.astype(int).tolist()}


def category_mean(cats: dict[str, dict[str, Any]], metrics_3d: bool) -> dict[str, Any]:
    """The ``mean`` section of ``metrics.json``: each metric averaged over the categories where it is finite, the
    3D metrics likewise (``meshes_empty`` summed), objects and views summed."""
    mean: dict[str, Any] = {}
    for key in METRIC_KEYS:
        values = [m[key] for m in cats.values() if m[key] is not None and np.isfinite(m[key])]
        mean[key] = float(np.mean(values)) if values else None
    if metrics_3d:
        mean.update(mean_surface(list(cats.values())))
    mean["objects"] = sum(m["objects"] for m in cats.values())
    mean["views"] = sum(m["views"] for m in cats.values())
    return mean


def merge_settings(settings: Sequence[dict[str, Any] | None]) -> dict[str, Any] | None:
    """The settings of evaluations of disjoint categories run side by side, as one record: the first part's, with
    every part's ``categories`` and the longest part's ``seconds`` (the wall time of the side-by-side run); the
    first part's as they are when any part has no settings.

    Example:
        >>> merge_settings([{"categories": "pen", "seconds": 4.0}, {"categories": "bottle", "seconds": 6.5}])
        {'categories': 'pen | bottle (2 processes side by side)', 'seconds': 6.5}
    """
    if not settings or any(s is None for s in settings):
        return settings[0] if settings else None
    categories = (
        " | ".join(str(s.get("categories", "")) for s in settings) + f" ({len(settings)} processes side by side)"
    )
    seconds = max(float(s.get("seconds", 0.0)) for s in settings)
    return {**settings[0], "categories": categories, "seconds": seconds}


def merge_metrics(parts: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """One method's ``metrics.json`` from evaluations of disjoint categories (run side by side, one per core):
    their categories together and the mean over all of them, as one evaluation of every category gives, with the
    parts' settings merged by :func:`merge_settings`.

    View stability, when every part carries it, is merged from the per-object records (:func:`merge_stability`).

    Raises:
        ValueError: when the parts are of different methods or splits, overlap in a category, or only some of them
            carry view stability.
    """
    if len({(p["method"], p["split"]) for p in parts}) != 1:
        raise ValueError("merge_metrics: the parts are of different methods or splits")
    with_stability = ["stability" in p for p in parts]
    if any(with_stability) and not all(with_stability):
        raise ValueError("merge_metrics: only some parts carry view stability")
    cats: dict[str, dict[str, Any]] = {}
    for part in parts:
        twice = sorted(set(part["categories"]) & set(cats))
        if twice:
            raise ValueError(f"merge_metrics: categories evaluated twice: {twice}")
        cats.update(part["categories"])
    metrics_3d = any("fscore_1cm" in m for m in cats.values())
    merged = {"categories": dict(sorted(cats.items())), "mean": category_mean(cats, metrics_3d)}
    if all(with_stability):
        merged["stability"] = merge_stability([p["stability"] for p in parts])
    settings = merge_settings([p.get("settings") for p in parts])
    return {**merged, "method": parts[0]["method"], "split": parts[0]["split"], "settings": settings}


def object_targets(obj: ObjectData, targets: list[int], scale: float) -> tuple[TargetSet, np.ndarray, np.ndarray]:
    """What a method must predict of ``obj`` at the target frames, and the truth there: the target set, labels
    (K, H, W) uint8 and RGB (K, H, W, 3) uint8 at ``scale`` × the dataset resolution."""
    intr = obj.record.intrinsics.scaled(scale)
    size = (intr.width, intr.height)
    target_set = TargetSet(intr, np.stack([obj.pose(i) for i in targets]), obj.record.background_color)
    gt = np.stack([resized(obj.affordance(i), size, nearest=True) for i in targets])
    gt_rgb = np.stack([resized(obj.rgb(i), size, nearest=False) for i in targets])
    return target_set, gt, gt_rgb


def surface_score(
    method: Method, obj: ObjectData, inputs: list[int], truth: SurfaceSamples | None, seed: int
) -> SurfaceScore | None:
    """The 3D scores of the method's mesh from ``inputs``; None without a mesh or without the truth (3D off)."""
    if truth is None:
        return None
    return score_mesh(method_mesh(method, obj, inputs), truth, sample_seed(seed, obj.record.object_id))


def stability_record(
    method: Method,
    obj: ObjectData,
    config: ProtocolConfig,
    targets: TargetSet,
    gt: np.ndarray,
    num_classes: int,
    first: tuple[Prediction, SurfaceScore | None],
    truth: SurfaceSamples | None,
) -> StabilityRecord:
    """Scores of ``obj`` from each of ``config.stability_views`` input-view sets at the same targets: the object's
    own 2D mIoU (its target views' confusion matrix) and F-score (None without a mesh or with 3D off). ``first``
    is the prediction and 3D score from the protocol's own inputs, reused."""
    order = view_order(len(obj), obj.record.object_id, config.seed)
    sets = input_sets(order, config.input_views, config.target_views, config.stability_views)
    mious, fscores = [], []
    for k, inputs in enumerate(sets):
        if k == 0:
            pred, score = first
        else:
            pred = method.predict(obj, inputs, targets)
            score = surface_score(method, obj, inputs, truth, config.seed)
        mious.append(mean_iou(confusion_matrix(gt, pred.labels, num_classes)))
        fscores.append(None if score is None else score["fscore_1cm"])
    return StabilityRecord(obj.record.object_id, obj.record.category, sets, mious, fscores)


def example_views(num_frames: int, object_id: str, config: ProtocolConfig, targets: list[int]) -> tuple[int, int]:
    """The figure's input frame and the index into ``targets`` of its shown target, the same for every method.

    The input is the first frame of the seeded order (an input of every method); the target is the frame at
    position ``target_views`` of that order, a target of every method given at most ``target_views`` inputs, so
    methods with 1 and 3 input views are shown at one camera. With more inputs than that, the first target.

    Example:
        >>> config = ProtocolConfig(input_views=1, target_views=5)
        >>> _, one = choose_views(30, "pen_0001", config)
        >>> _, three = choose_views(30, "pen_0001", ProtocolConfig(input_views=3, target_views=5))
        >>> a, i = example_views(30, "pen_0001", config, one)
        >>> b, j = example_views(30, "pen_0001", ProtocolConfig(input_views=3, target_views=5), three)
        >>> a == b and one[i] == three[j]
        True
    """
    order = view_order(num_frames, object_id, config.seed)
    shown = order[config.target_views] if config.target_views < len(order) else -1
    return order[0], targets.index(shown) if shown in targets else 0


def _example(obj: ObjectData, views: tuple[int, int], gt: np.ndarray, gt_rgb: np.ndarray, pred: Prediction) -> dict:
    """One object's picture for the figure (input, ground truth, prediction) at ``views`` (:func:`example_views`)."""
    frame, k = views
    size = (gt.shape[2], gt.shape[1])
    return {
        "object_id": obj.record.object_id,
        "input": resized(obj.rgb(frame), size, nearest=False),
        "gt_rgb": gt_rgb[k],
        "gt_labels": gt[k],
        "labels": pred.labels[k],
        "rgb": None if pred.rgb is None else pred.rgb[k],
    }


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
        config: view choice, resolution, 3D metrics and view stability.
        split: name recorded in the result.
        num_classes: affordance classes including background.
        keep_examples: keep this many objects' pictures (input, ground truth, prediction; :func:`example_views`)
            for figures.
    """
    result = EvalResult(method.name, split, num_classes, metrics_3d=config.metrics_3d)
    result.stability_views = config.stability_views
    for obj in objects:
        category = obj.record.category
        inputs, targets = choose_views(len(obj), obj.record.object_id, config)
        target_set, gt, gt_rgb = object_targets(obj, targets, config.scale)
        pred = method.predict(obj, inputs, target_set)
        result.add(category, gt, pred, gt_rgb)
        truth = true_samples(obj, config.seed) if config.metrics_3d else None
        score = surface_score(method, obj, inputs, truth, config.seed)
        if config.metrics_3d:
            result.add_surface(category, score)
        if config.stability_views:
            record = stability_record(method, obj, config, target_set, gt, num_classes, (pred, score), truth)
            result.stability.append(record)
        if len(result.examples) < keep_examples:
            views = example_views(len(obj), obj.record.object_id, config, targets)
            result.examples.append(_example(obj, views, gt, gt_rgb, pred))
    return result
