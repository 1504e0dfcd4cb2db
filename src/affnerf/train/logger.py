"""Where a run's numbers go: TensorBoard (``tb/``) and ``metrics.jsonl`` in the run folder, from rank 0 only."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

import numpy as np

if TYPE_CHECKING:
    from torch.utils.tensorboard import SummaryWriter


class MetricsLogger:
    """Scalars and images to TensorBoard and ``metrics.jsonl``; does nothing where ``enabled`` is false.

    Each call to :meth:`scalars` appends one JSON line ``{"step": step, **values}`` (keys in the order given) and
    one TensorBoard scalar per value.
    """

    def __init__(self, out: Path, enabled: bool) -> None:
        """Open (append to) ``out/metrics.jsonl`` and a TensorBoard writer on ``out/tb`` when ``enabled``."""
        self.enabled = enabled
        self.writer: SummaryWriter | None = None
        self.jsonl: TextIO | None = None
        if enabled:
            from torch.utils.tensorboard import SummaryWriter

            self.writer = SummaryWriter(str(out / "tb"))
            self.jsonl = open(out / "metrics.jsonl", "a")

    def scalars(self, step: int, values: dict[str, float]) -> None:
        """Record ``values`` at ``step``; the JSON line is flushed at once, so a killed run keeps it."""
        if self.writer is None or self.jsonl is None:
            return
        for key, value in values.items():
            self.writer.add_scalar(key, value, step)
        self.jsonl.write(json.dumps({"step": step, **values}) + "\n")
        self.jsonl.flush()

    def images(self, step: int, images: list[np.ndarray]) -> None:
        """Record (H, W, 3) uint8 pictures at ``step`` as ``val/object_<i>``."""
        if self.writer is None:
            return
        for i, image in enumerate(images):
            self.writer.add_image(f"val/object_{i}", image, step, dataformats="HWC")

    def close(self) -> None:
        """Flush and close the TensorBoard writer and the JSON lines file."""
        if self.writer is not None and self.jsonl is not None:
            self.writer.close()
            self.jsonl.close()
