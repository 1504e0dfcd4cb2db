"""What a result was measured on: machine, threads, software versions, time (benchmarks and Table 3 record it
beside their numbers, since a rerun on other library versions or another thread count need not give the same
bits)."""

from __future__ import annotations

import os
import platform
import time
from importlib import metadata
from typing import Any

#: Installed distributions whose versions a result records: those whose arithmetic it goes through.
RECORDED_PACKAGES = ("numpy", "scipy", "trimesh", "embreex", "scikit-image", "coacd", "pybullet")


def package_versions(names: tuple[str, ...] = RECORDED_PACKAGES) -> dict[str, str | None]:
    """The installed version of each distribution, None where it is not installed.

    Example:
        >>> package_versions(("numpy", "no-such-package-here"))["no-such-package-here"] is None
        True
    """
    versions: dict[str, str | None] = {}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def describe_machine() -> dict[str, Any]:
    """CPU count, platform, Python, torch and its thread count, the :data:`RECORDED_PACKAGES` versions, and the
    GPU if torch sees one."""
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
        info["torch_threads"] = torch.get_num_threads()
        info["device"] = torch.cuda.get_device_name(0) if torch.cuda.is_available() else "cpu"
    except ImportError:
        info["device"] = "cpu"
    info["packages"] = package_versions()
    return info
