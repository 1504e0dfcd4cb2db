"""Planning parallel-jaw grasps on a (labelled) mesh: antipodal candidates, parallel local search, jaw closing,
collision check, Ferrari-Canny ranking.

Use::

    obj = load_grasp_object("affordance_model.ply", need_affordance=True)   # affnerf.grasp.target
    grasps = plan_grasps(obj, PlanConfig(affordance="grasp", num=16))        # best first
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from scipy.spatial import cKDTree

from affnerf.errors import AffnerfError
from affnerf.grasp.contacts import Contacts, close_jaws, hold_contacts, score_contacts
from affnerf.grasp.gripper import ParallelJawGripper, grasp_pose
from affnerf.grasp.quality import MU
from affnerf.grasp.refine import RefineConfig, refine_grasps
from affnerf.grasp.target import GraspObject
from affnerf.vocab import affordance_id

#: Default ``part_margin`` of a restricted grasp, metres (benchmarks/results/grasp_margin.md).
PART_MARGIN = 0.01
#: Default ``min_confidence`` of a restricted grasp: 0, off (0.7-0.9 cost lift-and-disturb on validation objects,
#: benchmarks/results/grasp_confidence.md).
MIN_CONFIDENCE = 0.0
#: Sampled antipodal pairs are always at least this much narrower than the gripper's opening, metres.
PAIR_CLEARANCE = 0.004
#: Default ``width_clearance``, for an exact mesh: nothing beyond the pairs' own clearance.
WIDTH_CLEARANCE = 0.0
#: ``width_clearance`` on a mesh predicted from one image, whose widths are uncertain (chosen on validation
#: objects: benchmarks/results/grasp_clearance.md).
PREDICTED_CLEARANCE = 0.012
#: Default ``rank`` of the planner's grasps.
RANK = "epsilon"


@dataclass(frozen=True)
class PlanConfig:
    """Settings of the planner.

    Attributes:
        affordance: restrict contacts to faces of this affordance (``none`` = anywhere).
        num: grasps returned (best first).
        candidates: antipodal pairs sampled before the local search (times ``approaches`` grasps are refined).
        approaches: approach directions tried per pair (around the closing axis).
        mu: friction coefficient (sampling cone and quality).
        seed: random seed.
        refine: the local search (``steps=0`` skips it).
        surface_samples: surface points of the refinement (and of the collision check, with the vertices).
        collision_tolerance: penetration of the gripper into the surface still accepted, metres.
        part_margin: with ``affordance``, contacts keep at least this distance (metres) from the surface of every
            other label: the allowed part is shrunk away from its boundaries, where a predicted model's labels are
            least reliable. Halved while that would leave nothing (:func:`shrink_part`), and when no grasp survives
            on what is left the whole part is planned on, so a margin never costs an object its grasps (0 = the
            whole part).
        width_clearance: grasps, sampled pairs and refined grasps alike, are at most the gripper's opening less
            this wide (metres; the pairs also keep :data:`PAIR_CLEARANCE`). 0 on an exact mesh (the local search may
            open a grasp up to the full opening); more on a mesh predicted from one image, whose widths are
            uncertain, so that a grasp planned across a section the model made too narrow is not one the true
            object cannot fit.
        min_confidence: with ``affordance``, on a mesh whose faces say how sure its predicting field is of their
            labels (``GraspObject.face_confidence``), contacts are first sought on the faces of the part at least
            this sure (and confirmed, where the mesh has a second prediction); then on the whole part. 0 = off.
        rank: what orders the grasps, best first: ``epsilon`` (Ferrari-Canny, every wrench direction at once) or
            ``hold`` (the least weight the contacts carry at the centroid while the object turns ±90° about the
            closing axis, :func:`~affnerf.grasp.quality.hold_quality`; canonical +z up), ties broken by epsilon.
    """

    affordance: str = "none"
    num: int = 64
    candidates: int = 64
    approaches: int = 4
    mu: float = MU
    seed: int = 0
    refine: RefineConfig = field(default_factory=RefineConfig)
    surface_samples: int = 1500
    collision_tolerance: float = 0.001
    part_margin: float = PART_MARGIN
    width_clearance: float = WIDTH_CLEARANCE
    min_confidence: float = MIN_CONFIDENCE
    rank: Literal["epsilon", "hold"] = RANK


@dataclass
class Grasp:
    """One planned grasp.

    Attributes:
        pose: (4, 4) grasp frame in the object's frame (see :mod:`affnerf.grasp.gripper`).
        width: opening at contact, metres.
        contacts: (2, 3) contact points of finger 1 and finger 2.
        epsilon: Ferrari-Canny quality.
        affordance: affordance names at the two contacts.
        hold: the least weight the contacts carry while the object turns about the closing axis, in units of the
            total normal force (:func:`~affnerf.grasp.quality.hold_quality`).
    """

    pose: np.ndarray
    width: float
    contacts: np.ndarray
    epsilon: float
    affordance: list[str]
    hold: float = 0.0

    def to_json(self) -> dict:
        return {
            "pose": np.round(self.pose, 6).tolist(),
            "width": round(float(self.width), 6),
            "contacts": np.round(self.contacts, 6).tolist(),
            "epsilon": float(self.epsilon),
            "affordance": list(self.affordance),
            "hold": round(float(self.hold), 6),
        }


def allowed_faces(obj: GraspObject, affordance: str) -> np.ndarray | None:
    """(F,) bool faces of ``affordance`` that contacts may lie on, or None for anywhere."""
    if affordance == "none":
        return None
    if obj.face_affordance is None:
        raise AffnerfError(f"{obj.name}: mesh has no 'affordance' property to restrict grasps to {affordance!r}")
    mask = obj.face_affordance == affordance_id(affordance)
    if not mask.any():
        raise AffnerfError(f"{obj.name}: no surface labelled {affordance!r} to grasp")
    return mask


def shrink_part(vertices: np.ndarray, faces: np.ndarray, part: np.ndarray, margin: float) -> np.ndarray:
    """The faces of a part at least ``margin`` from the rest of the surface; where nothing is that far, the
    margin halved up to three times, then the whole part.

    Args:
        vertices: (V, 3); faces: (F, 3); part: (F,) bool; margin: metres.

    Returns:
        (F,) bool, a non-empty subset of ``part`` when ``part`` is non-empty.
    """
    if margin <= 0 or part.all() or not part.any():
        return part
    others = np.unique(faces[~part])
    distance, _ = cKDTree(vertices[others]).query(vertices[faces[part]].mean(axis=1))
    for tried in (margin, margin / 2, margin / 4, margin / 8):
        kept = distance >= tried
        if kept.any():
            out = np.zeros_like(part)
            out[np.flatnonzero(part)[kept]] = True
            return out
    return part


def widest_pair(gripper: ParallelJawGripper, clearance: float = WIDTH_CLEARANCE) -> float:
    """The widest antipodal pair the planner samples, metres: the opening less ``clearance``, and never less than
    :data:`PAIR_CLEARANCE` below it."""
    return gripper.max_opening - max(PAIR_CLEARANCE, clearance)


def sample_antipodal(
    obj: GraspObject,
    count: int,
    rng: np.random.Generator,
    mask: np.ndarray | None,
    mu: float,
    gripper: ParallelJawGripper,
    clearance: float = WIDTH_CLEARANCE,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Antipodal candidate pairs: a surface point, a ray into the object within half the friction cone, and
    the surface where it comes out, both on allowed faces and at most :func:`widest_pair` apart.

    Returns:
        centres (K, 3), closing axes (K, 3) from the first point to the second, widths (K,).
    """
    points, faces = obj.sample_surface(count * 4, rng, mask)
    if not len(points):
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    inward = -obj.face_normals[faces]
    tilt = rng.normal(size=inward.shape) * math.tan(math.atan(mu) / 2.0) / 2.0
    dirs = inward + tilt - (tilt * inward).sum(1, keepdims=True) * inward
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    ray, face, t, _ = obj.caster.cast(points + 1e-5 * dirs, dirs)
    exits = (obj.face_normals[face] * dirs[ray]).sum(1) > math.cos(math.atan(mu))  # leaves through a facing side
    ok = exits & (t < widest_pair(gripper, clearance)) & (t > 0.002)
    if mask is not None:
        ok &= mask[face]
    ray, t = ray[ok], t[ok]
    a, b = points[ray], points[ray] + t[:, None] * dirs[ray]
    keep = slice(0, count)
    return ((a + b) / 2.0)[keep], dirs[ray][keep], t[keep]


def _approaches(axes: np.ndarray, per_pair: int, rng: np.random.Generator) -> np.ndarray:
    """(K * per_pair, 3) approach directions around each axis (evenly spaced, randomly phased)."""
    out = []
    for axis in axes:
        helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        u = np.cross(axis, helper)
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        phase = rng.uniform(0, 2 * math.pi)
        for k in range(per_pair):
            ang = phase + 2 * math.pi * k / per_pair
            out.append(math.cos(ang) * u + math.sin(ang) * v)
    return np.asarray(out).reshape(-1, 3)


def collides(
    poses: np.ndarray, widths: np.ndarray, gripper: ParallelJawGripper, points: np.ndarray, tolerance: float
) -> np.ndarray:
    """(G,) whether the gripper (at each opening) cuts into the object: surface points (P, 3) deeper than
    ``tolerance`` inside a finger or the palm. Only the points within the gripper's reach of each grasp centre
    (:meth:`ParallelJawGripper.reach` at the widest opening, a k-d tree query) are tested.

    Args:
        poses: (G, 4, 4) grasp frames; widths: (G,) openings, metres; points: (P, 3).
    """
    hit = np.zeros(len(poses), bool)
    if not len(poses) or not len(points):
        return hit
    near = cKDTree(points).query_ball_point(poses[:, :3, 3], gripper.reach(float(widths.max())))
    for i, (pose, width, index) in enumerate(zip(poses, widths, near, strict=True)):
        if not index:
            continue
        local = (points[index] - pose[:3, 3]) @ pose[:3, :3]  # (n, 3) in the grasp frame
        hit[i] = any(np.all(np.abs(local - c) < h - tolerance, axis=1).any() for c, h in gripper.boxes(width))
    return hit


def _suppress(poses: np.ndarray, order: np.ndarray, distance: float = 0.004, angle_deg: float = 15.0) -> list[int]:
    """Greedy non-maximum suppression: keep grasps (in ``order``) not too close to an already kept one."""
    kept: list[int] = []
    cos_limit = math.cos(math.radians(angle_deg))
    for i in order:
        close = False
        for j in kept:
            same_place = np.linalg.norm(poses[i, :3, 3] - poses[j, :3, 3]) < distance
            same_axis = abs(poses[i, :3, 0] @ poses[j, :3, 0]) > cos_limit
            same_approach = poses[i, :3, 2] @ poses[j, :3, 2] > cos_limit
            if same_place and same_axis and same_approach:
                close = True
                break
        if not close:
            kept.append(int(i))
    return kept


def trusted_part(obj: GraspObject, part: np.ndarray, min_confidence: float) -> np.ndarray | None:
    """(F,) bool faces of ``part`` whose labels the mesh vouches for: confirmed by a second prediction
    (``obj.face_agrees``) and at least ``min_confidence`` sure (``obj.face_confidence``), each where the mesh has
    it; None when it has neither, or when no face (or every face) of the part passes."""
    trusted = part.copy()
    if obj.face_agrees is not None:
        trusted &= obj.face_agrees
    if obj.face_confidence is not None and min_confidence > 0:
        trusted &= obj.face_confidence >= min_confidence - 1e-9
    return trusted if trusted.any() and not np.array_equal(trusted, part) else None


def part_masks(obj: GraspObject, part: np.ndarray, margin: float, min_confidence: float = 0.0) -> list[np.ndarray]:
    """The (F,) bool surfaces a restricted grasp is planned on, in turn until one yields grasps: the faces of
    ``part`` the mesh vouches for (:func:`trusted_part`), shrunk by ``margin`` (:func:`shrink_part`), then whole;
    then ``part`` shrunk, then whole. A repeated mask is left out.
    """
    tried: list[np.ndarray] = []
    trusted = trusted_part(obj, part, min_confidence)
    for base in ([trusted] if trusted is not None else []) + [part]:
        for mask in (shrink_part(obj.vertices, obj.faces, base, margin), base):
            if not any(np.array_equal(mask, t) for t in tried):
                tried.append(mask)
    return tried


def plan_grasps(
    obj: GraspObject, config: PlanConfig = PlanConfig(), gripper: ParallelJawGripper = ParallelJawGripper()
) -> list[Grasp]:
    """Plan grasps, best first (at most ``config.num``; fewer when fewer survive the checks). Restricted to a
    part, on the first of :func:`part_masks` where any survive (the part the mesh vouches for, the part shrunk by
    the margin, the whole part)."""
    part = allowed_faces(obj, config.affordance)
    if part is None:
        return _plan_on(obj, None, config, gripper)
    for mask in part_masks(obj, part, config.part_margin, config.min_confidence):
        grasps = _plan_on(obj, mask, config, gripper)
        if grasps:
            return grasps
    return []


def _plan_on(obj: GraspObject, mask: np.ndarray | None, config: PlanConfig, gripper: ParallelJawGripper) -> list[Grasp]:
    """Grasps with both contacts on ``mask`` faces ((F,) bool; None = anywhere), best first."""
    rng = np.random.default_rng(config.seed)
    centres, axes, widths = sample_antipodal(
        obj, config.candidates, rng, mask, config.mu, gripper, config.width_clearance
    )
    if not len(centres):
        return []
    approaches = _approaches(axes, config.approaches, rng)
    centres, axes, widths = (np.repeat(a, config.approaches, axis=0) for a in (centres, axes, widths))
    surface, faces = obj.sample_surface(config.surface_samples, rng, mask)
    if config.refine.steps > 0:
        centres, axes, approaches, widths = refine_grasps(
            centres,
            axes,
            approaches,
            widths,
            surface,
            obj.face_normals[faces],
            obj.centroid,
            obj.radius,
            gripper,
            config.refine,
        )
    poses = np.stack([grasp_pose(c, a, r) for c, a, r in zip(centres, axes, approaches, strict=True)])
    contacts = close_jaws(obj, poses, gripper)
    check_points = np.concatenate([obj.sample_surface(config.surface_samples, rng)[0], obj.vertices])
    valid = contacts.valid & (contacts.width <= gripper.max_opening - config.width_clearance)
    if mask is not None:
        valid &= mask[np.maximum(contacts.faces, 0)].all(axis=1)
    valid[valid] = ~collides(poses[valid], contacts.width[valid], gripper, check_points, config.collision_tolerance)
    kept, epsilon, hold = _rank(obj, replace(contacts, valid=valid), poses, config)
    return [
        Grasp(
            poses[i],
            float(contacts.width[i]),
            contacts.points[i],
            float(epsilon[i]),
            obj.label_names(contacts.faces[i]),
            float(hold[i]),
        )
        for i in kept
    ]


def _rank(
    obj: GraspObject, contacts: Contacts, poses: np.ndarray, config: PlanConfig
) -> tuple[list[int], np.ndarray, np.ndarray]:
    """The grasps kept, best first by ``config.rank`` with near-duplicates suppressed (at most ``config.num``
    indices of the ``contacts.valid`` ones), and every grasp's epsilon and hold (G,) (0 where not scored: the hold
    is computed for every valid grasp only when it ranks them, else for the kept ones alone)."""
    epsilon = score_contacts(obj, contacts, poses, config.mu)
    by_hold = config.rank == "hold"
    hold = hold_contacts(obj, contacts, poses, config.mu) if by_hold else np.zeros(len(poses))
    candidates = np.flatnonzero(contacts.valid)
    keys = (-epsilon[candidates], -hold[candidates]) if by_hold else (-epsilon[candidates],)
    kept = _suppress(poses, candidates[np.lexsort(keys)])[: config.num]
    if not by_hold:
        only = np.zeros_like(contacts.valid)
        only[kept] = True
        hold = hold_contacts(obj, replace(contacts, valid=only), poses, config.mu)
    return kept, epsilon, hold
