"""``affnerf metrics``: score two folders of label PNGs with the same file names, so any method's outputs can be
compared with the same protocol (conventions §5)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import yaml

from affnerf.data.images import read_labels
from affnerf.errors import input_error
from affnerf.eval.protocol import EvalResult, Prediction
from affnerf.vocab import AFFORDANCE_CLASSES


def read_category_map(path: Path) -> dict[str, str]:
    """A JSON or YAML mapping of label file name (relative to the folders, or its stem) to category."""
    path = Path(path)
    if not path.is_file():
        raise input_error(path, "category map not found")
    try:
        data = yaml.safe_load(path.read_text())  # YAML reads JSON too
    except yaml.YAMLError as exc:
        raise input_error(path, f"not valid JSON or YAML ({' '.join(str(exc).split())})") from None
    if not isinstance(data, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in data.items()):
        raise input_error(path, "expected a mapping of file name -> category name")
    return data


def _category(name: str, mapping: dict[str, str] | None, map_path: Path | None) -> str:
    if mapping is None:
        return "all"
    for key in (name, Path(name).stem, Path(name).name):
        if key in mapping:
            return mapping[key]
    raise input_error(map_path, f"no category for {name}")


def score_folders(
    pred: Path, gt: Path, category_map: Path | None = None, num_classes: int | None = None
) -> dict[str, Any]:
    """Metrics (conventions §5 schema, method ``folder``) of every label PNG under ``gt`` against its namesake under
    ``pred``.

    Raises:
        AffnerfError: for a missing folder, a ground-truth file without prediction, mismatched sizes, or labels
            outside the vocabulary.
    """
    pred, gt = Path(pred), Path(gt)
    for folder in (pred, gt):
        if not folder.is_dir():
            raise input_error(folder, "folder not found")
    names = sorted(p.relative_to(gt).as_posix() for p in gt.rglob("*.png"))
    if not names:
        raise input_error(gt, "no label PNGs in the ground-truth folder")
    mapping = read_category_map(category_map) if category_map is not None else None
    n = num_classes or len(AFFORDANCE_CLASSES)
    result = EvalResult(method=pred.name, split=gt.name, num_classes=n)
    for name in names:
        if not (pred / name).is_file():
            raise input_error(pred / name, "prediction missing for this ground-truth file")
        g = read_labels(gt / name, n)
        p = read_labels(pred / name, n, (g.shape[1], g.shape[0]))
        result.add(
            _category(name, mapping, category_map), g[None], Prediction(p[None]), np.zeros((1, *g.shape, 3), np.uint8)
        )
    return result.to_json()


def metrics_text(metrics: dict[str, Any]) -> str:
    """A plain-text table of the metrics per category and their mean."""
    keys = ("mIoU", "PA", "MPA", "mIoU_object", "PA_object", "MPA_object")
    lines = [f"{'category':<14}" + "".join(f"{k:>12}" for k in keys) + f"{'views':>7}"]
    rows = list(metrics["categories"].items()) + [("mean", metrics["mean"])]
    for name, m in rows:
        cells = "".join(f"{m[k]:>12.3f}" if m.get(k) is not None else f"{'–':>12}" for k in keys)
        lines.append(f"{name:<14}{cells}{m.get('views', 0):>7}")
    return "\n".join(lines)
