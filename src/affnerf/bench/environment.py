"""What a benchmark result was measured on: machine, software versions, time."""

from __future__ import annotations

import os
import platform
import time
from typing import Any


def describe_machine() -> dict[str, Any]:
    """CPU count, platform, Python and library versions, and the GPU if torch sees one."""
    info: dict[str, Any] = {
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
    }
    try:
        import torch

        info["torch"] = torch.__version__
        info["device"] = torch.cuda.get_device_name(0) if torch.cuda.is_available() else "cpu"
    except ImportError:
        info["device"] = "cpu"
    return info
