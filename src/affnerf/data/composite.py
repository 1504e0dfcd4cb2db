"""Synthetic photos for training the object segmenter: rendered objects pasted onto clutter.

A training photo is one object of a dataset (its RGB render and its mask, ``affordance > 0``) pasted at a random
size and place onto a random background, with or without a soft drop shadow. Backgrounds are either a crop of a
photograph that ships inside scikit-image (no download; a documented list can be held out for testing) or
"dead leaves" clutter: overlapping random shapes of random colours, a classic stand-in for natural image
statistics. When the viewer's package (viser) is installed, views of the ten real scenes it ships as environment
maps (Poly Haven panoramas, CC0: an interior, a warehouse, a studio, streets, a park, a forest, ...) join the
photographs. Whole things cut out of the photographs (their salient subjects) can be pasted as distractors, so
that "the thing the photo is about" is not taken for the object. Colour, blur and noise are changed afterwards by
the trainer (:mod:`affnerf.train.segmenter`).
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFilter
from scipy import ndimage

#: scikit-image's bundled photographs that the composite benchmark pastes objects onto
#: (``benchmarks/bench_segment.py``): never used for training, so that benchmark measures unseen backgrounds.
HELD_OUT_BACKGROUNDS = ("astronaut", "coffee", "chelsea", "rocket", "hubble_deep_field", "ihc")
#: Range of the object's larger side as a share of the photo's height.
OBJECT_SCALE = (0.2, 0.85)
#: Share of training photos with a subject (:func:`training_photo`) and its larger side's range (share of H).
SUBJECT_SHARE, SUBJECT_SCALE = 0.5, (0.4, 0.95)


@dataclass
class Cutout:
    """One rendered object view cut to its bounding box.

    Attributes:
        rgb: (h, w, 3) uint8 render inside the object's box.
        mask: (h, w) bool object pixels.
    """

    rgb: np.ndarray
    mask: np.ndarray


def cut_to_box(rgb: np.ndarray, mask: np.ndarray) -> Cutout | None:
    """The (H, W, 3) render and (H, W) mask cut to the mask's bounding box (``None`` when the mask is empty)."""
    rows, cols = np.flatnonzero(mask.any(1)), np.flatnonzero(mask.any(0))
    if not len(rows):
        return None
    box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    return Cutout(np.ascontiguousarray(rgb[box]), np.ascontiguousarray(mask[box]))


def largest_component(mask: np.ndarray) -> np.ndarray:
    """The largest 8-connected component of an (H, W) bool mask (all False when it is empty).

    Example:
        >>> m = np.zeros((3, 6), bool); m[0, 0] = m[1, 3:6] = True
        >>> largest_component(m).sum()
        np.int64(3)
    """
    labels, count = ndimage.label(mask, structure=np.ones((3, 3)))
    if count <= 1:
        return mask.astype(bool)
    sizes = ndimage.sum(mask, labels, index=np.arange(1, count + 1))
    return labels == int(np.argmax(sizes)) + 1


def _package_folder(name: str) -> Path | None:
    """The installed package ``name``'s folder, without importing it (``None`` when it is not installed)."""
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations)))


def panorama_views(panorama: np.ndarray, views: int = 4) -> list[np.ndarray]:
    """``views`` (H/2, W/3, 3) views around an (H, W, 3) equirectangular panorama: its band within 45° of the
    horizon (where it is least stretched), cut into pieces of 120° starting every 360°/``views`` (wrapping round).

    Example:
        >>> [v.shape for v in panorama_views(np.zeros((512, 1024, 3), np.uint8))]
        [(256, 341, 3), (256, 341, 3), (256, 341, 3), (256, 341, 3)]
    """
    h, w = panorama.shape[:2]
    band = np.concatenate([panorama[h // 4 : h - h // 4]] * 2, axis=1)
    width = w // 3
    return [np.ascontiguousarray(band[:, k * w // views : k * w // views + width]) for k in range(views)]


def scene_photos() -> list[np.ndarray]:
    """(H, W, 3) uint8 views of the real-scene panoramas that viser ships (:func:`panorama_views`); empty when viser
    is not installed."""
    folder = _package_folder("viser")
    if folder is None:
        return []
    views = []
    for path in sorted((folder / "_assets" / "hdri").glob("*.jpg")):
        views += panorama_views(np.asarray(Image.open(path).convert("RGB")))
    return views


def photo_library(exclude: tuple[str, ...] = HELD_OUT_BACKGROUNDS, scenes: bool = True) -> list[np.ndarray]:
    """(H, W, 3) uint8 photographs bundled with scikit-image (grey ones as three equal channels), except the
    file stems in ``exclude``, and with ``scenes`` the views of :func:`scene_photos`; empty when neither package
    is installed."""
    folder = _package_folder("skimage")
    photos = []
    paths = sorted((folder / "data").glob("*.png")) + sorted((folder / "data").glob("*.jpg")) if folder else []
    for path in paths:
        if path.stem.startswith(tuple(exclude)):
            continue
        image = np.asarray(Image.open(path).convert("RGB"))
        if min(image.shape[:2]) >= 64:
            photos.append(image)
    return photos + (scene_photos() if scenes else [])


def random_colour(rng: np.random.Generator) -> tuple[int, int, int]:
    """A random RGB colour (0..255 each)."""
    return tuple(int(c) for c in rng.integers(0, 256, 3))


def dead_leaves(rng: np.random.Generator, size: tuple[int, int], shapes: int = 120) -> np.ndarray:
    """(H, W, 3) uint8 clutter of ``shapes`` random ellipses, rectangles and polygons (``size`` = (W, H)), their
    sizes drawn from a power law so a few are large and many small, blurred a little."""
    w, h = size
    image = Image.new("RGB", size, random_colour(rng))
    draw = ImageDraw.Draw(image)
    for _ in range(shapes):
        r = max(w, h) * 0.5 * rng.uniform(0.02, 1.0) ** 2.5
        cx, cy = rng.uniform(-0.1 * w, 1.1 * w), rng.uniform(-0.1 * h, 1.1 * h)
        kind = rng.integers(3)
        if kind == 0:
            draw.ellipse([cx - r, cy - r * rng.uniform(0.3, 1), cx + r, cy + r], fill=random_colour(rng))
        elif kind == 1:
            draw.rectangle([cx - r, cy - r * rng.uniform(0.1, 1), cx + r, cy + r], fill=random_colour(rng))
        else:
            angles = np.sort(rng.uniform(0, 2 * np.pi, rng.integers(3, 7)))
            pts = [(cx + r * np.cos(a), cy + r * np.sin(a)) for a in angles]
            draw.polygon(pts, fill=random_colour(rng))
    return np.asarray(image.filter(ImageFilter.GaussianBlur(rng.uniform(0, 1.5))))


def photo_crop(rng: np.random.Generator, photo: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """(H, W, 3) uint8 random crop of ``photo`` at a random zoom (``size`` = (W, H)), flipped at random, its
    channels re-weighted at random (a grey photo gets a colour cast)."""
    w, h = size
    zoom = max(w / photo.shape[1], h / photo.shape[0]) * rng.uniform(1.0, 2.5)
    big = Image.fromarray(photo).resize((max(w, round(photo.shape[1] * zoom)), max(h, round(photo.shape[0] * zoom))))
    x, y = rng.integers(0, big.width - w + 1), rng.integers(0, big.height - h + 1)
    crop = np.asarray(big.crop((x, y, x + w, y + h)), np.float32)
    if rng.random() < 0.5:
        crop = crop[:, ::-1]
    gains = rng.uniform(0.6, 1.3, 3) if rng.random() < 0.5 else np.ones(3)
    return np.clip(crop * gains, 0, 255).astype(np.uint8)


def random_background(rng: np.random.Generator, size: tuple[int, int], photos: list[np.ndarray]) -> np.ndarray:
    """(H, W, 3) uint8: a photo crop, dead-leaves clutter, or (a quarter of the time) the two blended; a photo only
    when ``photos`` has one."""
    if not photos or rng.random() < 0.4:
        return dead_leaves(rng, size)
    crop = photo_crop(rng, photos[rng.integers(len(photos))], size)
    if rng.random() < 0.25:
        t = rng.uniform(0.3, 0.7)
        crop = (t * crop + (1 - t) * dead_leaves(rng, size)).astype(np.uint8)
    return crop


def paste(
    rng: np.random.Generator, background: np.ndarray, cutout: Cutout, scale: tuple[float, float] = OBJECT_SCALE
) -> tuple[np.ndarray, np.ndarray]:
    """The cutout pasted onto the (H, W, 3) uint8 background at a random size (its larger side a share
    ``scale`` of H, at most the width) and place, with a soft drop shadow half of the time.

    Returns:
        (H, W, 3) uint8 photo and (H, W) float32 alpha of the object (its true mask is ``alpha > 0.5``).
    """
    h, w = background.shape[:2]
    ch, cw = cutout.mask.shape
    side = min(rng.uniform(*scale) * h, 0.95 * w, 0.95 * h * max(cw, ch) / ch)
    size = (max(2, round(cw * side / max(cw, ch))), max(2, round(ch * side / max(cw, ch))))
    rgb = np.asarray(Image.fromarray(cutout.rgb).resize(size, Image.BILINEAR), np.float32)
    alpha = np.asarray(Image.fromarray(cutout.mask.astype(np.uint8) * 255).resize(size, Image.BILINEAR), np.float32)
    x, y = rng.integers(0, w - size[0] + 1), rng.integers(0, h - size[1] + 1)
    full = np.zeros((h, w), np.float32)
    full[y : y + size[1], x : x + size[0]] = alpha / 255.0
    canvas = background.astype(np.float32)
    if rng.random() < 0.5:
        dx, dy = rng.integers(-12, 13, 2)
        shade = np.roll(np.roll(full, dy, 0), dx, 1)
        shade = ndimage.gaussian_filter(shade, rng.uniform(2, 8))
        canvas *= 1.0 - rng.uniform(0.2, 0.6) * shade[..., None]
    patch = np.zeros_like(canvas)
    patch[y : y + size[1], x : x + size[0]] = rgb
    out = full[..., None] * patch + (1.0 - full[..., None]) * canvas
    return np.clip(np.round(out), 0, 255).astype(np.uint8), full


def fragment(rng: np.random.Generator, cutout: Cutout) -> Cutout | None:
    """A random window (30-70 % of each side) of a cutout, its colours shuffled between channels: a shaded,
    rendered-looking piece that is not a whole object (``None`` when the window holds no object pixel)."""
    h, w = cutout.mask.shape
    fh, fw = max(2, round(h * rng.uniform(0.3, 0.7))), max(2, round(w * rng.uniform(0.3, 0.7)))
    y, x = rng.integers(0, h - fh + 1), rng.integers(0, w - fw + 1)
    window = (slice(y, y + fh), slice(x, x + fw))
    return cut_to_box(cutout.rgb[window][..., rng.permutation(3)], cutout.mask[window])


def training_photo(
    rng: np.random.Generator,
    cutout: Cutout,
    photos: list[np.ndarray],
    size: tuple[int, int],
    distractors: list[Cutout] = (),
    subjects: list[Cutout] = (),
) -> tuple[np.ndarray, np.ndarray]:
    """One synthetic photo of ``size`` (W, H): (H, W, 3) uint8 image and (H, W) bool true mask.

    Half of the time one of ``subjects`` (a whole thing cut out of a photograph) is pasted large into the
    background first, which the object may then lie on. Up to two fragments (:func:`fragment`) of ``distractors``
    follow, so that a rendered look alone does not make an object: the network has to find a whole one."""
    background = random_background(rng, size, photos)
    if len(subjects) and rng.random() < SUBJECT_SHARE:
        background, _ = paste(rng, background, subjects[rng.integers(len(subjects))], scale=SUBJECT_SCALE)
    for _ in range(rng.integers(0, 3) if len(distractors) else 0):
        piece = fragment(rng, distractors[rng.integers(len(distractors))])
        if piece is not None:
            background, _ = paste(rng, background, piece, scale=(0.1, 0.4))
    rgb, alpha = paste(rng, background, cutout)
    return rgb, alpha > 0.5
