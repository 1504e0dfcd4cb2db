"""The paper's sampling rule: each step takes several objects; for each, one random view goes through the
encoders and the rays are drawn from its OTHER views (with ``input_views`` > 1, for multi-view baselines,
several distinct views are encoded and the rays come from the rest).

Each rank of a distributed run walks its own slice of a per-epoch shuffle of the training objects, so ranks draw
different objects; the walk and the random draws are plain state (epoch, position, generator state), saved in
checkpoints so a resumed run continues with exactly the same data. With 3D supervision on, a
:class:`PointSampler` draws each step's points for the same objects from their cached point sets.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from affnerf.data.crop import crop_outside, mark_outside, resample_to_crop
from affnerf.rendering.rays import pixel_rays
from affnerf.train.cache import ObjectFrames, part_edge_index
from affnerf.train.mirror import flipped_views, reflection
from affnerf.train.pixels import draw_edge_pixels, draw_pixels, input_view_chances, other_views
from affnerf.train.points import PointSet

if TYPE_CHECKING:
    from affnerf.train.config import TrainConfig


@dataclass
class RayBatch:
    """One training step's data.

    Attributes:
        images: (B, V, 3, S, S) float encoder crops in [0, 1].
        input_intrinsics: (B, V, 4) the crops' fl_x, fl_y, cx, cy.
        input_poses: (B, V, 4, 4) the encoded views' camera-to-world poses.
        input_depth: (B, V, S, S) true z-depth (m, 0 = no surface) at the crops' pixels (GSNeRF's source-view depth
            supervision), the nearest pixel of the cached depth map.
        input_labels: (B, V, S, S) true affordance ids at the crops' pixels (0 = background), the nearest pixel of
            the cached label map (AFF-NeRF's input-view labelling, ``ModelConfig.view_affordance_weight``).
        ray_object: (R,) index of each ray's object in ``images``.
        origins: (R, 3) ray origins.
        dirs: (R, 3) ray directions (unit length along the camera axis).
        rgb: (R, 3) target colours in [0, 1].
        labels: (R,) target affordance ids.
        depth: (R,) target z-depth in metres (0 = the ray meets no surface).
        background: (R, 3) background colour behind each ray.
        encoder_view: (B, V) frame indices of each object's encoded views.
        ray_view: (R,) frame index each ray comes from.
        object_ids: the B objects' dataset ids.
        reflect: (B, 3) signs by which each object's canonical frame is mirrored this step (all ones: not
            mirrored; :mod:`affnerf.train.mirror`): its rays above already are, its 3D points are drawn so.
    """

    images: torch.Tensor
    input_intrinsics: torch.Tensor
    input_poses: torch.Tensor
    input_depth: torch.Tensor
    input_labels: torch.Tensor
    ray_object: torch.Tensor
    origins: torch.Tensor
    dirs: torch.Tensor
    rgb: torch.Tensor
    labels: torch.Tensor
    depth: torch.Tensor
    background: torch.Tensor
    encoder_view: torch.Tensor
    ray_view: torch.Tensor
    object_ids: list[str]
    reflect: torch.Tensor

    def to(self, device: torch.device | str) -> RayBatch:
        """The batch with every tensor on ``device``."""
        moved = {k: (v.to(device) if isinstance(v, torch.Tensor) else v) for k, v in self.__dict__.items()}
        return RayBatch(**moved)


class RaySampler:
    """Draws :class:`RayBatch` es following the paper's rule.

    Args:
        objects: the training objects' frames (each with at least two views).
        objects_per_step: objects per step (per rank).
        rays_per_step: rays per step (per rank), spread evenly over the objects.
        foreground_fraction: share of rays drawn on the object rather than uniformly over the image.
        seed: seed of the run.
        input_views: views encoded per object (1 for AFF-NeRF).
        rank: this process's rank.
        world: number of processes.
        outline_fraction: share of rays drawn near the object (:func:`draw_pixels`' ``near``), taken from the
            uniform ones; 0 keeps the paper's rule and its exact sequence of draws.
        outline_radius: their band's half-width in pixels of the frames.
        edge_fraction: share of rays drawn near a part edge inside the object (:func:`draw_edge_pixels`), taken from
            the foreground ones; 0 keeps the draws as they were.
        edge_radius: their band's half-width in pixels of the frames.
        cut_input_weight: how much a frame whose object touches the image border counts, against a whole one, in
            the choice of encoded views (:func:`input_view_chances`); 1 keeps the uniform choice and its draws.
        outside: the model's ``crop_outside``: ``checker`` marks where each encoded crop leaves its frame.
        mirror_fraction: chance that an object's encoded views are flipped left-right this step and its rays
            mirrored to match (:mod:`affnerf.train.mirror`); 0 keeps the draws as they were.
        mirror_axes: each object's mirror axis (:func:`affnerf.train.mirror.mirror_axis`; -1 = never mirrored),
            needed when ``mirror_fraction`` > 0.
    """

    def __init__(
        self,
        objects: list[ObjectFrames],
        objects_per_step: int,
        rays_per_step: int,
        foreground_fraction: float,
        seed: int,
        rank: int = 0,
        world: int = 1,
        input_views: int = 1,
        outline_fraction: float = 0.0,
        outline_radius: int = 0,
        edge_fraction: float = 0.0,
        edge_radius: int = 0,
        cut_input_weight: float = 1.0,
        outside: str = "background",
        mirror_fraction: float = 0.0,
        mirror_axes: list[int] | None = None,
    ) -> None:
        if not objects:
            raise ValueError("no training objects")
        if foreground_fraction < 0 or outline_fraction < 0 or foreground_fraction + outline_fraction > 1:
            raise ValueError(
                f"ray shares must be >= 0 and sum to at most 1, not {foreground_fraction} + {outline_fraction}"
            )
        if not 0 <= cut_input_weight <= 1:
            raise ValueError(f"the cut input views' weight is in [0, 1], not {cut_input_weight}")
        if not 0 <= edge_fraction <= foreground_fraction:
            raise ValueError(f"the part edges' share is in [0, {foreground_fraction}], not {edge_fraction}")
        if not 0 <= mirror_fraction <= 1 or (mirror_fraction > 0 and len(mirror_axes or []) != len(objects)):
            raise ValueError(f"the mirror chance is in [0, 1] with an axis for each object, not {mirror_fraction}")
        for o in objects:
            if len(o) < input_views + 1:
                raise ValueError(
                    f"object {o.object_id} has {len(o)} views; "
                    f"{input_views} encoded and at least one for rays are needed"
                )
        self.input_views = input_views
        self.objects = objects
        self.objects_per_step = objects_per_step
        self.rays_per_step = rays_per_step
        self.foreground_fraction = foreground_fraction
        self.outline_fraction, self.outline_radius = outline_fraction, outline_radius
        self.edge_fraction, self.edge_radius = edge_fraction, edge_radius
        self._edges = [part_edge_index(np.asarray(o.labels)) for o in objects] if edge_fraction else []
        self.cut_input_weight, self.outside = cut_input_weight, outside
        self.mirror_fraction, self.mirror_axes = mirror_fraction, list(mirror_axes or [-1] * len(objects))
        self._input_chances = (
            [input_view_chances(np.asarray(o.labels), cut_input_weight, input_views) for o in objects]
            if cut_input_weight < 1
            else [None] * len(objects)
        )
        self.seed, self.rank, self.world = seed, rank, world
        self.epoch, self.position = 0, 0
        self.rng = np.random.default_rng([seed, rank, 17])
        self._order = self._epoch_order(0)

    @classmethod
    def for_config(
        cls,
        objects: list[ObjectFrames],
        config: TrainConfig,
        rank: int = 0,
        world: int = 1,
        mirror_axes: list[int] | None = None,
    ) -> RaySampler:
        """The sampler of a training config: its objects, rays and ray shares a step, its seed, its encoded
        views (one more for the view-consistency loss's second view) and its mirror chance, with each object's
        ``mirror_axes``."""
        views = config.input_views + (1 if config.view_consistency_weight > 0 else 0)
        return cls(
            objects,
            config.objects_per_step,
            config.rays_per_step,
            config.foreground_fraction,
            config.seed,
            rank,
            world,
            views,
            config.outline_fraction,
            config.outline_radius,
            config.edge_fraction,
            config.edge_radius,
            config.cut_input_weight,
            config.model.crop_outside,
            config.mirror_fraction,
            mirror_axes,
        )

    def _epoch_order(self, epoch: int) -> np.ndarray:
        """This rank's objects for ``epoch``: its slice of a shuffle shared by all ranks."""
        perm = np.random.default_rng([self.seed, epoch, 29]).permutation(len(self.objects))
        mine = perm[self.rank :: self.world]
        return mine if len(mine) else perm[self.rank % len(perm) :: len(perm)]

    def _next_objects(self) -> list[int]:
        chosen = []
        while len(chosen) < self.objects_per_step:
            if self.position >= len(self._order):
                self.epoch += 1
                self.position = 0
                self._order = self._epoch_order(self.epoch)
            chosen.append(int(self._order[self.position]))
            self.position += 1
        return chosen

    def next_batch(self) -> RayBatch:
        """Draw one step's objects, encoder views and rays."""
        chosen = self._next_objects()
        counts = np.full(len(chosen), self.rays_per_step // len(chosen))
        counts[: self.rays_per_step % len(chosen)] += 1
        images, enc_views, parts = [], [], []
        for slot, (oi, count) in enumerate(zip(chosen, counts, strict=True)):
            obj = self.objects[oi]
            enc = self.rng.choice(len(obj), self.input_views, replace=False, p=self._input_chances[oi])
            views = other_views(self.rng, len(obj), enc, int(count))
            share = self.rng.random(int(count))
            fg = share < self.foreground_fraction
            near = None
            if self.outline_fraction:
                near = ~fg & (share < self.foreground_fraction + self.outline_fraction)
            u, v = draw_pixels(self.rng, obj, views, fg, near, self.outline_radius)
            if self.edge_fraction:
                on_edge = share < self.edge_fraction
                edges, shape = self._edges[oi], obj.labels.shape[1:]
                u, v = draw_edge_pixels(self.rng, edges, shape, views, on_edge, u, v, self.edge_radius)
            crop_depth, crop_labels = crop_maps(obj, enc)
            crops = encoder_crops(obj, enc, self.outside)
            seen = (crops, obj.crop_intrinsics[enc], obj.poses[enc], crop_depth, crop_labels)
            signs = np.ones(3)
            if self.mirror_fraction and self.mirror_axes[oi] >= 0 and self.rng.random() < self.mirror_fraction:
                signs = reflection(self.mirror_axes[oi])
                seen = flipped_views(*seen, signs)
            images.append(seen)
            enc_views.append(enc)
            parts.append((slot, obj, views, u, v, signs))
        return _assemble(images, enc_views, parts, [self.objects[i].object_id for i in chosen])

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to continue the same sequence of batches."""
        return {"epoch": self.epoch, "position": self.position, "rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.epoch, self.position = int(state["epoch"]), int(state["position"])
        self.rng.bit_generator.state = state["rng"]
        self._order = self._epoch_order(self.epoch)


def encoder_crops(obj: ObjectFrames, enc: np.ndarray, outside: str = "background") -> np.ndarray:
    """(V, S, S, 3) uint8 cached crops of the encoded views ``enc``, their pixels outside the frame marked by a
    checkerboard when ``outside`` is ``checker`` (``ModelConfig.crop_outside``)."""
    crops = np.asarray(obj.crops[enc])
    if outside != "checker":
        return crops
    shape, size = obj.labels.shape[1:], crops.shape[1]
    outside_masks = [crop_outside(shape, obj.intrinsics, obj.crop_intrinsics[e], size) for e in enc]
    return np.stack([mark_outside(c, m) for c, m in zip(crops, outside_masks, strict=True)])


def crop_maps(obj: ObjectFrames, enc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(V, S, S) depth and (V, S, S) affordance ids of each encoder view's crop (V may be 0: a method fitted
    without input views)."""
    size = obj.crops.shape[1]

    def crops(maps: np.ndarray, dtype: type) -> np.ndarray:
        seen = [resample_to_crop(maps[e], obj.intrinsics, obj.crop_intrinsics[e], size) for e in enc]
        return np.stack(seen).astype(dtype) if seen else np.zeros((0, size, size), dtype)

    return crops(obj.depth, np.float32), crops(obj.labels, np.uint8)


def _assemble(images: list[tuple], enc_views: list[np.ndarray], parts: list[tuple], ids: list[str]) -> RayBatch:
    ray_object, pix, views, poses, intr, rgb, labels, depth, bg = [], [], [], [], [], [], [], [], []
    reflect = np.stack([p[5] for p in parts])
    for slot, obj, view, u, v, _ in parts:
        n = len(view)
        ray_object.append(np.full(n, slot))
        pix.append(np.stack([u, v], 1))
        views.append(view)
        poses.append(obj.poses[view])
        intr.append(np.broadcast_to(obj.intrinsics, (n, 4)))
        rgb.append(obj.rgb[view, v, u])
        labels.append(obj.labels[view, v, u])
        depth.append(obj.depth[view, v, u])
        bg.append(np.broadcast_to(obj.background, (n, 3)))
    origins, dirs = pixel_rays(
        torch.from_numpy(np.concatenate(pix)),
        torch.from_numpy(np.concatenate(intr)),
        torch.from_numpy(np.concatenate(poses)),
    )
    ray_signs = torch.from_numpy(reflect[np.concatenate(ray_object)])
    origins, dirs = origins * ray_signs, dirs * ray_signs
    return RayBatch(
        images=torch.from_numpy(np.stack([i[0] for i in images])).permute(0, 1, 4, 2, 3).float() / 255.0,
        input_intrinsics=torch.from_numpy(np.stack([i[1] for i in images])).float(),
        input_poses=torch.from_numpy(np.stack([i[2] for i in images])).float(),
        input_depth=torch.from_numpy(np.stack([i[3] for i in images])).float(),
        input_labels=torch.from_numpy(np.stack([i[4] for i in images])).long(),
        ray_object=torch.from_numpy(np.concatenate(ray_object)).long(),
        origins=origins.float(),
        dirs=dirs.float(),
        rgb=torch.from_numpy(np.concatenate(rgb)).float() / 255.0,
        labels=torch.from_numpy(np.concatenate(labels)).long(),
        depth=torch.from_numpy(np.concatenate(depth)).float(),
        background=torch.from_numpy(np.concatenate(bg)).float(),
        encoder_view=torch.from_numpy(np.stack(enc_views)).long(),
        ray_view=torch.from_numpy(np.concatenate(views)).long(),
        object_ids=ids,
        reflect=torch.from_numpy(reflect).float(),
    )


@dataclass
class PointBatch:
    """One step's 3D supervision points (K per object of the step's ray batch).

    Attributes:
        points: (P, 3) canonical positions; point_object: (P,) index of each point's object in the ray batch;
        occupancy: (P,) float 0/1 targets; labels: (P,) affordance ids (0 = no target); distance: (P,) float
        truncated signed distances (metres, negative inside).
    """

    points: torch.Tensor
    point_object: torch.Tensor
    occupancy: torch.Tensor
    labels: torch.Tensor
    distance: torch.Tensor

    def to(self, device: torch.device | str) -> PointBatch:
        """The batch on ``device``."""
        return PointBatch(*(getattr(self, f.name).to(device) for f in fields(self)))


class PointSampler:
    """Draws ``per_object`` points (uniformly, with replacement) from each object's point set.

    Its generator is its own (seeded by the run's seed and rank), so turning points on leaves the ray batches
    unchanged; its state goes into checkpoints like the ray sampler's.

    Args:
        point_sets: object id -> its :class:`~affnerf.train.points.PointSet`.
        per_object: K, points per object and step.
        seed, rank: the run's seed and this process's rank.
    """

    def __init__(self, point_sets: dict[str, PointSet], per_object: int, seed: int, rank: int = 0) -> None:
        self.point_sets, self.per_object = point_sets, per_object
        self.rng = np.random.default_rng([seed, rank, 41])

    def draw(self, object_ids: list[str], reflect: np.ndarray | None = None) -> PointBatch:
        """K points of each of the ray batch's objects, in its order, each object's mirrored by its (3,) signs
        in the (B, 3) ``reflect`` (the ray batch's; :mod:`affnerf.train.mirror`)."""
        parts = []
        for slot, object_id in enumerate(object_ids):
            pts = self.point_sets[object_id]
            index = np.sort(self.rng.integers(0, len(pts), self.per_object))  # sorted: memory-map friendly
            slots = np.full(len(index), slot)
            xyz = pts.points[index] if reflect is None else pts.points[index] * reflect[slot].astype(np.float32)
            parts.append((xyz, slots, pts.occupancy[index], pts.labels[index], pts.distance[index]))
        xyz, obj, occ, labels, distance = (np.concatenate(p) for p in zip(*parts, strict=True))
        return PointBatch(
            torch.from_numpy(xyz).float(),
            torch.from_numpy(obj).long(),
            torch.from_numpy(occ).float(),
            torch.from_numpy(labels).long(),
            torch.from_numpy(distance).float(),
        )

    def state_dict(self) -> dict[str, Any]:
        return {"rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.rng.bit_generator.state = state["rng"]
