"""Process groups for multi-GPU (or multi-process CPU) training under ``torchrun``.

``torchrun --nproc_per_node N affnerf train ...`` sets RANK, LOCAL_RANK and WORLD_SIZE; each process then joins
one group (nccl on GPUs, gloo on CPUs). Without those variables the run is a single process.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import torch
import torch.distributed as dist


@dataclass(frozen=True)
class Context:
    """This process's place in the run.

    Attributes:
        rank: global rank (0 writes checkpoints and logs).
        world: number of processes.
        device: the device this process computes on.
    """

    rank: int
    world: int
    device: torch.device

    @property
    def is_main(self) -> bool:
        return self.rank == 0

    @property
    def distributed(self) -> bool:
        return self.world > 1


def setup(device: str) -> Context:
    """Join the process group if launched by ``torchrun``, and pick this process's device.

    Args:
        device: ``auto``, ``cpu`` or ``cuda``.
    """
    use_cuda = torch.cuda.is_available() if device == "auto" else device == "cuda"
    if use_cuda and not torch.cuda.is_available():
        raise RuntimeError("--device cuda asked for, but CUDA is not available")
    world = int(os.environ.get("WORLD_SIZE", "1"))
    rank = int(os.environ.get("RANK", "0"))
    local = int(os.environ.get("LOCAL_RANK", "0"))
    if use_cuda:
        torch.cuda.set_device(local)
        dev = torch.device("cuda", local)
    else:
        dev = torch.device("cpu")
    if world > 1 and not dist.is_initialized():
        dist.init_process_group(backend="nccl" if use_cuda else "gloo")
    return Context(rank=rank, world=world, device=dev)


def barrier(ctx: Context) -> None:
    """Wait for every process (no-op alone)."""
    if ctx.distributed:
        dist.barrier()


def gather_objects(ctx: Context, value: object) -> list[object]:
    """Every process's ``value``, in rank order (a one-item list alone)."""
    if not ctx.distributed:
        return [value]
    out: list[object] = [None] * ctx.world
    dist.all_gather_object(out, value)
    return out


def mean_across(ctx: Context, values: torch.Tensor) -> torch.Tensor:
    """The mean of a tensor over processes (itself alone)."""
    if not ctx.distributed:
        return values
    summed = values.detach().clone()
    dist.all_reduce(summed)
    return summed / ctx.world


def teardown(ctx: Context) -> None:
    """Leave the process group."""
    if ctx.distributed and dist.is_initialized():
        dist.destroy_process_group()
