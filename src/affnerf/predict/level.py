"""The density level of one object's mesh: the model's ``surface_density``, lowered for an object whose field is
diffuse so that the mesh fills what the field renders.

A model trained from one image is unsure where a large or hollow object's walls are: its density rises slowly over
several centimetres (a bucket's cavity holds a density of 20-40 /m where the truth is empty), so a single level
tuned over all objects meshes such an object far inside its rendered outline, while a thin, sharp object (a pen)
is meshed well at that level. The rule here compares two silhouettes of the object's density grid along each axis
of the canonical frame:

- the rendered one: rays along the axis whose optical depth (the integral of density) exceeds ``optical_depth``,
  what volume rendering shows as opaque;
- the mesh's one at level L: rays along which the density somewhere exceeds L (the outline of the level-L
  surface seen along that axis).

The level whose silhouettes agree best (mean IoU over the three axes) is the object's own level; the mesh uses it
when it is below ``surface_density`` and ``surface_density`` otherwise, so sharp objects keep the calibrated
level. ``optical_depth`` and ``surface_density`` are chosen together on validation objects by
``affnerf eval calibrate`` (conventions §5) and stored with the model; 0 switches the rule off.
"""

from __future__ import annotations

import numpy as np

#: Candidate levels (per metre) of the silhouette match, log-spaced.
LEVEL_CANDIDATES = tuple(float(v) for v in np.geomspace(2.0, 200.0, 33))


def axis_silhouettes(volume: np.ndarray, spacing: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per axis of a (R, R, R) density grid, the (R, R) maximum and (R, R) optical depth (sum × spacing) along it.

    Example:
        >>> v = np.zeros((4, 4, 4)); v[1, 2, :] = 10.0
        >>> peak, depth = axis_silhouettes(v, 0.5)
        >>> float(peak[2][1, 2]), float(depth[2][1, 2]), float(depth[0][2, 3])
        (10.0, 20.0, 5.0)
    """
    peaks = [volume.max(axis=a) for a in range(3)]
    depths = [volume.sum(axis=a) * spacing for a in range(3)]
    return peaks, depths


def silhouette_iou(a: np.ndarray, b: np.ndarray) -> float:
    """IoU of two boolean images; 1 when both are empty.

    Example:
        >>> silhouette_iou(np.array([True, True, False]), np.array([True, False, False]))
        0.5
    """
    union = int(np.logical_or(a, b).sum())
    return 1.0 if union == 0 else int(np.logical_and(a, b).sum()) / union


def silhouette_level(
    volume: np.ndarray,
    spacing: float,
    optical_depth: float,
    prefer: float = 50.0,
    candidates: tuple[float, ...] = LEVEL_CANDIDATES,
) -> float | None:
    """The candidate level whose axis silhouettes best match where the grid's optical depth exceeds
    ``optical_depth``; None when nothing is that opaque.

    Args:
        volume: (R, R, R) density (per metre) indexed [x, y, z], grid spacing ``spacing`` metres.
        optical_depth: optical depth along an axis above which a ray counts as rendered opaque.
        prefer: among equally good levels (a sharp object's outline is the same for every level below its
            density), the one closest to this (in ratio) wins; it is always a candidate itself.
        candidates: levels to try (per metre).
    """
    candidates = tuple(sorted({*candidates, float(prefer)}))
    peaks, depths = axis_silhouettes(volume, spacing)
    rendered = [d > optical_depth for d in depths]
    if not any(r.any() for r in rendered):
        return None
    scores = [
        np.mean([silhouette_iou(r, p > level) for r, p in zip(rendered, peaks, strict=True)]) for level in candidates
    ]
    best = max(scores)
    tied = [level for level, score in zip(candidates, scores, strict=True) if score == best]
    return float(min(tied, key=lambda level: abs(np.log(level / prefer))))


def object_level(volume: np.ndarray, spacing: float, surface_density: float, optical_depth: float) -> float:
    """The level of one object's mesh: :func:`silhouette_level` when it is below ``surface_density``, else
    ``surface_density`` (always, when ``optical_depth`` is 0).

    Example:
        >>> v = np.zeros((8, 8, 8)); v[2:6, 2:6, 2:6] = 12.0     # a diffuse cube: 12 /m inside
        >>> object_level(v, 0.02, 35.0, 0.5) < 12.0 < object_level(v, 0.02, 35.0, 0.0)
        True
    """
    if optical_depth <= 0:
        return float(surface_density)
    level = silhouette_level(volume, spacing, optical_depth, prefer=surface_density)
    return float(surface_density) if level is None else min(float(surface_density), level)
