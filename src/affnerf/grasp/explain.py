"""Why planning found no grasp (conventions §6): the narrowest width between antipodal surfaces found on the
wanted affordance, set against the gripper's opening, and what to change."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from affnerf.grasp.gripper import ParallelJawGripper
from affnerf.grasp.planner import PlanConfig, allowed_faces, widest_pair
from affnerf.grasp.size import extent
from affnerf.grasp.target import GraspObject
from affnerf.vocab import AFFORDANCE_CLASSES, affordance_id


def narrowest_width(
    obj: GraspObject, mask: np.ndarray | None, mu: float, samples: int = 2000, seed: int = 0
) -> float | None:
    """Smallest distance (m) from a surface point on ``mask`` faces (F,) straight through the object to a facing
    side within the friction cone (``mu``), also on ``mask``; None when no such pair is found.

    Ignores the gripper's opening; pairs closer than 2 mm (slivers, mesh noise) are skipped.
    """
    points, faces = obj.sample_surface(samples, np.random.default_rng(seed), mask)
    if not len(points):
        return None
    inward = -obj.face_normals[faces]
    ray, face, t, _ = obj.caster.cast(points + 1e-5 * inward, inward)
    ok = ((obj.face_normals[face] * inward[ray]).sum(1) > math.cos(math.atan(mu))) & (t > 0.002)
    if mask is not None:
        ok &= mask[face]
    return float(t[ok].min()) if ok.any() else None


def _other_affordances(obj: GraspObject, wanted: str, mu: float) -> dict[str, float]:
    """Narrowest width (m) of each other affordance on the mesh that has antipodal pairs."""
    if obj.face_affordance is None:
        return {}
    out = {}
    for label in np.unique(obj.face_affordance):
        name = AFFORDANCE_CLASSES[int(label)] if 0 < label < len(AFFORDANCE_CLASSES) else None
        if name is None or name == wanted:
            continue
        width = narrowest_width(obj, obj.face_affordance == affordance_id(name), mu, samples=500)
        if width is not None:
            out[name] = round(width, 4)
    return out


def _advice(
    width: float | None, fits: bool, others: dict[str, float], size: float, source: str, widest: float, clear: float
) -> list[str]:
    """What to change, most specific first (``widest`` the widest pair planned, ``clear`` the opening less it)."""
    fitting = sorted((w, name) for name, w in others.items() if w <= widest)
    advice = [f"--affordance {name} (narrowest {w:.3f} m)" for w, name in fitting]
    if not fits and width is not None:
        advice.append(f"a gripper opening of at least {width + clear:.3f} m (--max-opening)")
        if source != "transforms.json scale":
            advice.append(f"--object-size METRES if the object is smaller than the {size:.3f} m assumed ({source})")
    if fits:
        advice.append("more candidates (--candidates) or another approach: the fitting pairs collided")
    return advice


def explain_no_grasps(
    obj: GraspObject, config: PlanConfig, gripper: ParallelJawGripper, size_source: str = "mesh as given"
) -> dict[str, Any]:
    """Why :func:`~affnerf.grasp.planner.plan_grasps` found nothing on ``obj`` (metric), for ``grasps.json``:
    ``{"reason", "affordance", "narrowest_width", "max_opening", "other_affordances", "advice"}``."""
    width = narrowest_width(obj, allowed_faces(obj, config.affordance), config.mu)
    where = "the surface" if config.affordance == "none" else f"the {config.affordance!r} surface"
    widest = widest_pair(gripper, config.width_clearance)
    fits = width is not None and width <= widest
    if width is None:
        reason = f"no pair of facing sides found on {where}"
    elif not fits:
        reason = (
            f"the narrowest section of {where} is {width:.3f} m across, wider than the gripper's"
            f" {gripper.max_opening:.3f} m opening (less {round(gripper.max_opening - widest, 6)} m clearance)"
        )
    else:
        reason = f"sections of {where} fit the opening ({width:.3f} m) but every grasp collided or lost its contacts"
    others = _other_affordances(obj, config.affordance, config.mu) if config.affordance != "none" else {}
    return {
        "reason": reason,
        "affordance": config.affordance,
        "narrowest_width": None if width is None else round(width, 4),
        "max_opening": gripper.max_opening,
        "other_affordances": others,
        "advice": _advice(width, fits, others, extent(obj.vertices), size_source, widest, gripper.max_opening - widest),
    }


def no_grasp_text(why: dict[str, Any]) -> str:
    """The stderr message of :func:`explain_no_grasps`'s result.

    >>> no_grasp_text({"reason": "too wide", "advice": ["a wider gripper"]})
    'no grasp found: too wide. Try: a wider gripper.'
    """
    advice = "; ".join(why["advice"])
    return f"no grasp found: {why['reason']}." + (f" Try: {advice}." if advice else "")
