"""What a result records about where it was measured."""

from __future__ import annotations

import numpy as np
import torch

from affnerf.environment import RECORDED_PACKAGES, describe_machine, package_versions


def test_the_machine_record_names_threads_and_the_arithmetic_libraries_versions():
    info = describe_machine()
    assert info["torch"] == torch.__version__ and info["torch_threads"] == torch.get_num_threads() >= 1
    assert set(info["packages"]) == set(RECORDED_PACKAGES) and info["packages"]["numpy"] == np.__version__
    assert info["cpu_count"] >= 1 and info["device"] in {
        "cpu",
        *([torch.cuda.get_device_name(0)] if torch.cuda.is_available() else []),
    }


def test_a_missing_package_is_none_not_an_error():
    assert package_versions(("numpy", "no-such-distribution-xyz")) == {
        "numpy": np.__version__,
        "no-such-distribution-xyz": None,
    }
