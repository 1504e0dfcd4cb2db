"""Timing helpers: repeated measurements reported as median, min and max; peak memory."""

from __future__ import annotations

import resource
import statistics
import time
from collections.abc import Callable
from typing import Any

import torch


def sync(device: torch.device | str) -> None:
    """Wait for queued GPU work, so timings measure it."""
    if torch.device(device).type == "cuda":
        torch.cuda.synchronize()


def timed(fn: Callable[[], Any], repeats: int, warmup: int = 1, device: torch.device | str = "cpu") -> dict[str, float]:
    """Run ``fn`` ``warmup`` + ``repeats`` times; seconds of the measured runs as median, min, max."""
    for _ in range(warmup):
        fn()
    sync(device)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        sync(device)
        times.append(time.perf_counter() - start)
    return {"median": statistics.median(times), "min": min(times), "max": max(times), "repeats": repeats}


def peak_memory(device: torch.device | str) -> dict[str, float]:
    """Peak resident memory of this process (MiB) and, on a GPU, the most memory torch allocated (MiB)."""
    out = {"peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}
    if torch.device(device).type == "cuda":
        out["cuda_max_allocated_mib"] = torch.cuda.max_memory_allocated() / 2**20
    return out
