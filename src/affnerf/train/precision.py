"""Arithmetic precision of a training step's forward pass (``--precision``).

``fp32`` is the paper's. ``bf16`` runs the forward pass under :func:`torch.autocast` with bfloat16: matrix products
and convolutions (the encoders and the field's layers) in bfloat16, what autocast keeps in float32 (reductions,
losses) in float32, the weights, gradients and Adam state in float32 throughout. On CPUs with bfloat16 instructions
(AVX-512 BF16, AMX) and on recent GPUs a step is cheaper; on CPUs without them it can be slower
(``benchmarks/results/precision.md`` measures both the speed and what it does to quality).
"""

from __future__ import annotations

import contextlib
from typing import Literal, get_args

import torch

#: The values of ``--precision``.
Precision = Literal["fp32", "bf16"]
PRECISIONS: tuple[str, ...] = get_args(Precision)


def forward_precision(precision: str, device: torch.device) -> contextlib.AbstractContextManager:
    """The context a training step's forward pass and loss run in: autocast to bfloat16 on ``device``'s type for
    ``bf16``, nothing for ``fp32``.

    Example:
        >>> with forward_precision("bf16", torch.device("cpu")):
        ...     (torch.ones(2, 3) @ torch.ones(3, 1)).dtype
        torch.bfloat16
    """
    if precision == "fp32":
        return contextlib.nullcontext()
    return torch.autocast(device_type=device.type, dtype=torch.bfloat16)
