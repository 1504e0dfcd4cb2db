"""Multi-view consistency: a surface point seen in two views has one depth, one affordance and one part."""

from __future__ import annotations

import numpy as np
import pytest

from affnerf.data.cameras import Intrinsics, project, unproject_depth
from affnerf.data.generate import camera_poses
from affnerf.data.raycast import FrameCaster
from affnerf.objects.asset import merge_parts
from affnerf.objects.registry import CATEGORY_NAMES, make_object, object_seed


def _interior(labels: np.ndarray, depth: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N,) whether pixels (u, v) lie inside one part on a smooth surface: their 3x3 neighbourhood is foreground
    of the same label, with depths within 1 cm of each other (no silhouette or depth step nearby)."""
    h, w = labels.shape
    centre = labels[v, u]
    same = centre > 0
    lo, hi = depth[v, u].copy(), depth[v, u].copy()
    for dv in (-1, 0, 1):
        for du in (-1, 0, 1):
            vv, uu = np.clip(v + dv, 0, h - 1), np.clip(u + du, 0, w - 1)
            same &= labels[vv, uu] == centre
            lo, hi = np.minimum(lo, depth[vv, uu]), np.maximum(hi, depth[vv, uu])
    return same & (hi - lo < 0.01)


def _matches_nearby(labels: np.ndarray, u: np.ndarray, v: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """(N,) whether ``expected`` occurs in the 3x3 neighbourhood of pixels (u, v) of a label map."""
    h, w = labels.shape
    found = np.zeros(len(u), bool)
    for dv in (-1, 0, 1):
        for du in (-1, 0, 1):
            found |= labels[np.clip(v + dv, 0, h - 1), np.clip(u + du, 0, w - 1)] == expected
    return found


@pytest.mark.parametrize("category", CATEGORY_NAMES)
def test_points_reprojected_between_views_keep_depth_and_labels(category):
    asset = make_object(category, object_seed(5, category, 0))
    caster = FrameCaster(merge_parts(asset))
    intr = Intrinsics.from_fov(240, 180, np.radians(60))
    poses = camera_poses(5, category, 0, 8)
    frames = [caster.cast_frame(intr, p) for p in poses]
    eyes = poses[:, :3, 3] / np.linalg.norm(poses[:, :3, 3], axis=1, keepdims=True)
    checked = 0
    for a in range(len(poses)):
        b = int(np.argsort(-(eyes @ eyes[a]))[1])  # the view from the nearest direction
        fa, fb = frames[a], frames[b]
        fg = fa.depth > 0
        points = unproject_depth(fa.depth.astype(np.float64), intr, poses[a])[fg]
        pix, z = project(points, intr, poses[b])
        u, v = np.floor(pix[:, 0]).astype(int), np.floor(pix[:, 1]).astype(int)
        inside = (u >= 0) & (u < intr.width) & (v >= 0) & (v < intr.height) & (z > 0)
        # visible in B: the ray from B's camera towards the point first meets the surface at the point
        origin = poses[b][:3, 3]
        to_point = points[inside] - origin
        ray, _, t, _ = caster.cast(np.broadcast_to(origin, to_point.shape), to_point)
        hit_t = np.full(len(to_point), np.inf)
        hit_t[ray] = t
        visible = np.abs(hit_t - 1.0) * np.linalg.norm(to_point, axis=1) < 2e-4
        u, v, z = u[inside][visible], v[inside][visible], z[inside][visible]
        aff_a, part_a = fa.affordance[fg][inside][visible], fa.part[fg][inside][visible]
        # away from silhouettes and part boundaries, B's pixel has the point's depth and labels
        inner = _interior(fb.part, fb.depth, u, v)
        assert (np.abs(fb.depth[v, u] - z)[inner] < 0.01).mean() > 0.99
        assert (fb.part[v, u] == part_a)[inner].mean() > 0.995
        assert (fb.affordance[v, u] == aff_a)[inner].mean() > 0.995
        # next to a boundary, the point may land on the neighbouring pixel: its labels are within one pixel
        # (but where a part is under a pixel thin, such as a tapering tip, no pixel centre need hit it)
        assert _matches_nearby(fb.affordance, u, v, aff_a).mean() > 0.98
        assert _matches_nearby(fb.part, u, v, part_a).mean() > 0.98
        checked += int(inner.sum())
    assert checked > 500
