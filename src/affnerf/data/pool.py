"""Worker processes, each single-threaded and (on Linux) pinned to its own core from the start: dataset
generation renders objects in them, and Table 3's grasp evaluation (:mod:`affnerf.eval.grasps`) evaluates objects
in them.

Embree's thread pool (TBB) is sized by the cores a process may use when the library loads, and trimesh loads
it on import. Two workers free to use both cores each start a pool of two threads that fight over them
(measured: fewer frames per second than one process alone); a worker confined to one core from birth gets a
pool of one thread and the workers add up. A child inherits its parent's core mask when it is created, so the
parent narrows its own mask to one core while it starts each worker and restores it afterwards.

The OpenMP, BLAS and torch thread pools of a worker are sized to one thread too (:data:`SINGLE_THREAD`, set in
the child's environment before it imports anything): a floating-point sum split over threads is added in an
order that depends on their number, so a job's numbers would otherwise depend on the machine's core count (the
fit of a predicted model, measured: 1 and 2 threads give other grasps on every predicted mesh of Table 3).

A worker ends as soon as its parent does (:func:`_exit_with_parent`): a parent stopped by a signal (``kill``, a
job scheduler's time limit) runs no cleanup, and its workers would otherwise go on through the queued jobs.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import queue as queue_module
import threading
from collections.abc import Callable, Iterator, Sequence
from multiprocessing.connection import wait
from typing import Any

_POLL_SECONDS = 0.2
_EXIT_SECONDS = 30.0  #: how long a worker with no jobs left may take to exit before it is stopped

#: Environment of every worker: its thread pools hold one thread.
SINGLE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}


#: What a worker runs for each job: ``work(job, on_frame)`` returns the job's result (picklable); ``on_frame()`` is
#: called once per finished frame. It must be picklable itself (a module-level function or a partial of one).
Work = Callable[[Any, Callable[[], None]], Any]


def _exit_with_parent() -> None:
    """In a worker: end this process the moment its parent process ends, whatever it is doing (a watching
    thread waits on the parent's sentinel). A child process the job started, such as a CoACD decomposition
    (:mod:`affnerf.grasp.coacd_worker`), finishes its one task on its own."""
    parent = mp.parent_process()
    if parent is None:
        return

    def watch() -> None:
        wait([parent.sentinel])
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


def _worker_loop(work: Work, tasks: Any, results: Any, progress: Any) -> None:
    """Run jobs from ``tasks`` until a None arrives; report ("ok", result) or ("error", exception). Ends with the
    parent process (:func:`_exit_with_parent`)."""
    _exit_with_parent()
    while True:
        job = tasks.get()
        if job is None:
            return
        try:
            results.put(("ok", work(job, lambda: progress.put(1))))
        except BaseException as exc:  # handed to the parent, which raises it
            results.put(("error", exc))
            return


def _start_pinned(ctx: Any, count: int, args: tuple) -> list[Any]:
    """Start ``count`` single-threaded worker processes (:data:`SINGLE_THREAD`), the i-th confined to the i-th
    core (round robin) where the system can confine a process to a core (Linux; elsewhere, e.g. macOS, they are
    single-threaded but not pinned)."""
    original = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else set()
    cores = sorted(original)
    saved = {name: os.environ.get(name) for name in SINGLE_THREAD}
    os.environ.update(SINGLE_THREAD)
    procs = []
    try:
        for i in range(count):
            if len(cores) > 1:
                os.sched_setaffinity(0, {cores[i % len(cores)]})
            proc = ctx.Process(target=_worker_loop, args=args, daemon=True)
            proc.start()
            procs.append(proc)
    finally:
        if original:
            os.sched_setaffinity(0, original)
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
    return procs


def run_jobs(work: Work, jobs: Sequence[Any], workers: int, on_frames: Callable[[int], None]) -> Iterator[Any]:
    """Run ``work`` on each of ``jobs`` in ``workers`` pinned processes, yielding each job's result as it finishes.

    Args:
        work: what to do with one job (see :data:`Work`).
        jobs: picklable job descriptions.
        workers: number of processes.
        on_frames: called in this process with the number of frames finished since the last call.

    Raises:
        The first exception a job raised, after stopping every worker.
    """
    ctx = mp.get_context("spawn")
    tasks, results, progress = ctx.Queue(), ctx.Queue(), ctx.Queue()
    for job in jobs:
        tasks.put(job)
    for _ in range(workers):
        tasks.put(None)
    procs = _start_pinned(ctx, workers, (work, tasks, results, progress))
    try:
        remaining = len(jobs)
        while remaining:
            try:
                status, value = results.get(timeout=_POLL_SECONDS)
            except queue_module.Empty:
                on_frames(_drain(progress))
                if not any(p.is_alive() for p in procs):
                    raise RuntimeError("every worker stopped before finishing its jobs") from None
                continue
            on_frames(_drain(progress))
            if status == "error":
                raise value
            remaining -= 1
            yield value
        for proc in procs:  # each exits after its None, its progress written out first: the last frames count too
            proc.join(timeout=_EXIT_SECONDS)
        on_frames(_drain(progress))
    finally:
        for proc in procs:
            if proc.is_alive():
                proc.terminate()
            proc.join()


def _drain(progress: Any) -> int:
    count = 0
    while True:
        try:
            count += progress.get_nowait()
        except queue_module.Empty:
            return count
