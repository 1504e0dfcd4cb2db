"""Reading and writing the dataset's image maps (conventions §2), with one-line errors that name the file.

RGB is 8-bit PNG; depth is 16-bit PNG of z-depth in units of ``depth_unit_scale_factor`` metres (0 = no
surface); affordance and part maps are 8-bit PNGs of class and part ids.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from affnerf.errors import input_error

#: zlib level of written PNGs: 1 is several times faster to write than Pillow's default for a few % more bytes.
PNG_COMPRESS_LEVEL = 1


def write_rgb(path: Path, rgb: np.ndarray) -> None:
    """Write (H, W, 3) uint8 as an 8-bit RGB PNG."""
    Image.fromarray(np.ascontiguousarray(rgb, dtype=np.uint8), "RGB").save(path, compress_level=PNG_COMPRESS_LEVEL)


def write_depth(path: Path, depth: np.ndarray, unit: float = 0.001) -> None:
    """Write (H, W) z-depth in metres as a 16-bit PNG in units of ``unit`` metres (0 stays 0 = no surface)."""
    q = np.clip(np.round(np.asarray(depth, np.float64) / unit), 0, 65535).astype(np.uint16)
    Image.fromarray(q).save(path, compress_level=PNG_COMPRESS_LEVEL)


def write_labels(path: Path, labels: np.ndarray) -> None:
    """Write (H, W) uint8 ids as an 8-bit greyscale PNG."""
    Image.fromarray(np.ascontiguousarray(labels, dtype=np.uint8), "L").save(path, compress_level=PNG_COMPRESS_LEVEL)


def open_image(path: Path) -> Image.Image:
    """Open and fully decode an image, reporting a folder, a missing, corrupt or empty file as one line."""
    path = Path(path)
    if path.is_dir():
        raise input_error(path, "is a directory, not an image; give one image file (PNG, JPEG, ...)")
    if not path.is_file():
        raise input_error(path, "file not found")
    try:
        image = Image.open(path)
        image.load()
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise input_error(path, f"cannot read image ({exc})") from None
    if image.width == 0 or image.height == 0:
        raise input_error(path, "image has zero size")
    return image


def _check_size(path: Path, array: np.ndarray, size: tuple[int, int] | None) -> np.ndarray:
    if size is not None and (array.shape[1], array.shape[0]) != tuple(size):
        raise input_error(path, f"image is {array.shape[1]}x{array.shape[0]}, expected {size[0]}x{size[1]}")
    return array


def to_rgb8(image: Image.Image) -> np.ndarray:
    """(H, W, 3) uint8 from any Pillow mode: palette and grey are expanded, 16-bit scaled, alpha dropped."""
    if image.mode in ("I;16", "I;16B", "I;16L", "I"):
        a = np.asarray(image, dtype=np.float64)
        peak = 255.0 if image.mode == "I" and a.max(initial=0) <= 255 else 65535.0
        grey = np.clip(np.round(a / peak * 255.0), 0, 255).astype(np.uint8)
        return np.repeat(grey[..., None], 3, axis=2)
    if image.mode == "F":
        grey = np.clip(np.round(np.asarray(image) * 255.0), 0, 255).astype(np.uint8)
        return np.repeat(grey[..., None], 3, axis=2)
    return np.asarray(image.convert("RGB"), dtype=np.uint8)


def read_rgb(path: Path, size: tuple[int, int] | None = None) -> np.ndarray:
    """Read an image as (H, W, 3) uint8, whatever its mode.

    Args:
        path: the image file.
        size: expected (width, height), checked when given.
    """
    return _check_size(path, to_rgb8(open_image(path)), size)


def read_depth(path: Path, unit: float = 0.001, size: tuple[int, int] | None = None) -> np.ndarray:
    """Read a 16-bit depth PNG as (H, W) float32 metres (0 = no surface)."""
    image = open_image(path)
    if image.mode not in ("I;16", "I;16B", "I;16L", "I", "L"):
        raise input_error(path, f"depth image has mode {image.mode}, expected 16-bit greyscale")
    return _check_size(path, np.asarray(image, dtype=np.float64).astype(np.float32) * np.float32(unit), size)


def read_labels(path: Path, num_ids: int | None = None, size: tuple[int, int] | None = None) -> np.ndarray:
    """Read an 8-bit id map as (H, W) uint8.

    Args:
        path: the PNG.
        num_ids: when given, every id must be below it (e.g. the number of affordance classes).
        size: expected (width, height), checked when given.
    """
    image = open_image(path)
    if image.mode not in ("L", "P"):
        raise input_error(path, f"label image has mode {image.mode}, expected 8-bit greyscale ids")
    labels = np.asarray(image, dtype=np.uint8)  # a palette image's indices are the ids
    if num_ids is not None and labels.size and int(labels.max()) >= num_ids:
        raise input_error(path, f"label id {int(labels.max())} is outside the {num_ids} known ids")
    return _check_size(path, labels, size)
