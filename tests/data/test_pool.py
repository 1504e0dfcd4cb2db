"""Worker processes: results of every job, single-threaded workers, and systems that cannot pin a process."""

from __future__ import annotations

import os

from affnerf.data.pool import SINGLE_THREAD, run_jobs


def thread_settings(job: int, on_frame) -> tuple[int, dict[str, str | None]]:
    """The job and the thread-pool variables its worker sees (module level: a spawned worker imports it)."""
    on_frame()
    return job, {name: os.environ.get(name) for name in SINGLE_THREAD}


def test_every_job_runs_once_in_a_single_threaded_worker_and_the_parent_keeps_its_environment(monkeypatch):
    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    frames = []
    results = sorted(run_jobs(thread_settings, [3, 1, 2], 2, frames.append))
    assert [job for job, _ in results] == [1, 2, 3] and sum(frames) == 3
    assert all(settings == SINGLE_THREAD for _, settings in results)
    assert os.environ["OMP_NUM_THREADS"] == "2"


def test_workers_start_where_processes_cannot_be_pinned_to_a_core(monkeypatch):
    monkeypatch.delattr(os, "sched_getaffinity")  # as on macOS
    monkeypatch.delattr(os, "sched_setaffinity")
    assert sorted(job for job, _ in run_jobs(thread_settings, [1, 2], 2, lambda n: None)) == [1, 2]
