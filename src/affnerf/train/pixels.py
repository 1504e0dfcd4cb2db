"""Where a training step's rays land: which frames, and which pixels of them (on the object, near its outline, near
the edges between its parts, or anywhere), drawn from the frame cache's per-frame pixel indices
(:func:`affnerf.train.cache.pixel_index`). Pure functions of a random generator, used by
:class:`affnerf.train.sampler.RaySampler`; a share left at 0 draws nothing, so the paper's sequence of draws stays.
"""

from __future__ import annotations

import numpy as np

from affnerf.data.crop import touches_border
from affnerf.train.cache import ObjectFrames


def other_views(rng: np.random.Generator, num_views: int, excluded: np.ndarray, count: int) -> np.ndarray:
    """(count,) uniform frame indices in [0, num_views) that are never among ``excluded``.

    Example:
        >>> set(other_views(np.random.default_rng(0), 4, np.array([1, 2]), 100).tolist())
        {0, 3}
    """
    allowed = np.setdiff1d(np.arange(num_views), excluded)
    return allowed[rng.integers(0, len(allowed), count)]


def input_view_chances(labels: np.ndarray, cut_weight: float, views: int = 1) -> np.ndarray | None:
    """Chance of each frame to be an encoder's input when a frame whose object touches the image border (and may
    be cut off by it) counts ``cut_weight`` times a whole one.

    Args:
        labels: (N, H, W) affordance ids, 0 = background.
        cut_weight: in [0, 1]; 1 keeps the uniform choice.
        views: frames drawn together (without replacement) for one object.

    Returns:
        (N,) probabilities summing to 1, or None for the uniform choice (a weight of 1, an object none of whose
        frames is cut, or one with fewer than ``views`` frames that a draw could take).

    Example:
        >>> labels = np.zeros((3, 4, 4), np.uint8); labels[0, 1, 1] = labels[1, 0, 2] = labels[2, 2, 2] = 1
        >>> input_view_chances(labels, 0.0).tolist()
        [0.5, 0.0, 0.5]
    """
    cut = touches_border(labels > 0)
    whole = int((~cut).sum())
    if cut_weight >= 1 or whole == len(cut) or whole < (views if cut_weight == 0 else 1):
        return None
    weights = np.where(cut, cut_weight, 1.0)
    return weights / weights.sum()


def draw_pixels(
    rng: np.random.Generator,
    frames: ObjectFrames,
    views: np.ndarray,
    foreground: np.ndarray,
    near: np.ndarray | None = None,
    radius: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel (u, v) per ray: uniform over the image, uniform over the object's pixels, or near the object.

    Args:
        rng: random source.
        frames: the object's cached frames (for the image size and each frame's object pixels).
        views: (R,) frame of each ray.
        foreground: (R,) bool, rays that should land on the object (a frame showing no object falls back to
            uniform).
        near: (R,) bool or None, rays drawn near the object: an object pixel moved by a uniform integer offset in
            [-radius, radius] along u and along v (clipped to the image), so they cover the object and a band of
            ``radius`` pixels around its outline (uniform, as ``foreground``, where the frame shows no object).
            Not also ``foreground``.
        radius: the band's half-width in pixels of the frames.

    Returns:
        u (R,), v (R,) integer pixel indices.
    """
    _, h, w = frames.labels.shape
    flat = rng.integers(0, h * w, len(views))
    start, stop = frames.fg_offsets[views], frames.fg_offsets[views + 1]
    on_object = foreground if near is None else foreground | near
    pick = on_object & (stop > start)
    if pick.any():
        flat[pick] = indexed_pixels(rng, frames.fg_offsets, frames.fg_pixels, views, pick)
    u, v = flat % w, flat // w
    if near is not None:
        jitter_pixels(rng, u, v, pick & near, radius, (h, w))
    return u, v


def indexed_pixels(
    rng: np.random.Generator, offsets: np.ndarray, pixels: np.ndarray, views: np.ndarray, pick: np.ndarray
) -> np.ndarray:
    """(P,) flat pixel indices, one drawn uniformly for each of the P ``pick`` ed rays among its frame's entries of
    a per-frame index ((N + 1,) ``offsets`` into (M,) ``pixels``; every picked ray's frame must have one)."""
    start, stop = offsets[views], offsets[views + 1]
    return pixels[start[pick] + np.floor(rng.random(int(pick.sum())) * (stop - start)[pick]).astype(np.int64)]


def jitter_pixels(
    rng: np.random.Generator, u: np.ndarray, v: np.ndarray, chosen: np.ndarray, radius: int, shape: tuple[int, int]
) -> None:
    """Move the ``chosen`` rays' (R,) pixels u, v in place by a uniform integer offset in [-radius, radius] along
    each axis, clipped to the (H, W) image."""
    if chosen.any():
        offsets = rng.integers(-radius, radius + 1, (2, int(chosen.sum())))
        u[chosen] = np.clip(u[chosen] + offsets[0], 0, shape[1] - 1)
        v[chosen] = np.clip(v[chosen] + offsets[1], 0, shape[0] - 1)


def draw_edge_pixels(
    rng: np.random.Generator,
    edges: tuple[np.ndarray, np.ndarray],
    shape: tuple[int, int],
    views: np.ndarray,
    chosen: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    radius: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of the ``chosen`` rays moved near a part edge: a uniform edge pixel of the ray's frame shifted by a
    uniform integer offset in [-radius, radius] along u and along v (clipped to the image). A ray whose frame has no
    part edge keeps its pixel.

    Args:
        rng: random source.
        edges: (N + 1,) offsets and (M,) flat pixel indices of each frame's part edges
            (:func:`affnerf.train.cache.part_edge_index`).
        shape: (H, W) of the frames.
        views: (R,) frame of each ray; chosen: (R,) bool, the rays to move; u, v: (R,) their pixels so far.
        radius: the band's half-width in pixels.

    Returns:
        u (R,), v (R,) integer pixel indices (new arrays).
    """
    offsets, pixels = edges
    pick = chosen & (offsets[views + 1] > offsets[views])
    u, v = u.copy(), v.copy()
    if pick.any():
        flat = indexed_pixels(rng, offsets, pixels, views, pick)
        u[pick], v[pick] = flat % shape[1], flat // shape[1]
        jitter_pixels(rng, u, v, pick, radius, shape)
    return u, v
