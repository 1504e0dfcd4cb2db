"""``affnerf train``: presets chosen with ``--config``, any field overridable from the command line.

The preset (or a run's ``config.json`` given with ``--config-file``) supplies the defaults of every flag, so
``affnerf train --config small --model.field-width 128`` is the small preset with a wider field.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Annotated

import tyro

from affnerf.train.config import PRESETS, TrainConfig, read_config


def _flag_value(args: Sequence[str], flag: str) -> str | None:
    for i, arg in enumerate(args):
        if arg == flag and i + 1 < len(args):
            return args[i + 1]
        if arg.startswith(flag + "="):
            return arg.split("=", 1)[1]
    return None


def strip_flag(args: Sequence[str], flag: str) -> list[str]:
    """``args`` without ``flag VALUE`` / ``flag=VALUE``."""
    out, skip = [], False
    for arg in args:
        if skip:
            skip = False
        elif arg == flag:
            skip = True
        elif not arg.startswith(flag + "="):
            out.append(arg)
    return out


def train_defaults(args: Sequence[str]) -> TrainConfig:
    """The defaults the flags start from: ``--config-file FILE``, else the ``--config`` preset (paper)."""
    config_file = _flag_value(args, "--config-file")
    if config_file is not None:
        base = read_config(Path(config_file))
        return replace(base, resume=False)
    name = _flag_value(args, "--config") or "paper"
    base = PRESETS.get(name, PRESETS["paper"])  # an unknown name is reported by the parser
    return replace(base, data=tyro.MISSING, out=tyro.MISSING)  # type: ignore[arg-type]


def make_train_command(args: Sequence[str]) -> Callable[..., None]:
    """The ``train`` verb, its defaults taken from the preset or file named in ``args``."""
    defaults = train_defaults(args)

    def train(config: Annotated[TrainConfig, tyro.conf.arg(name="")] = defaults) -> None:
        """Train AFF-NeRF on a dataset (one CPU, one GPU, or many under torchrun).

        --config paper|small picks the preset; every field can be overridden (e.g. --model.field-width 128).
        --config-file RUN/config.json starts from a finished run's resolved config instead, to reproduce it.
        --steps is the run's total: --resume continues from the last checkpoint to the same total. The same command
        under `torchrun --nproc_per_node N` trains with DistributedDataParallel.
        """
        from affnerf.train.trainer import train as run

        summary = run(config)
        extra = "".join(f", {k} {v:.4g}" for k, v in summary.scalars.items() if k.startswith("val/"))
        print(f"trained to step {summary.step} in {summary.seconds:.0f} s{extra} -> {config.out}")

    return train
