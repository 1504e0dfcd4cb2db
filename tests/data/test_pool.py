"""Worker processes: results of every job, single-threaded workers, systems that cannot pin a process, and
workers that end with their parent."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

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


def sleep_and_report(job: str, on_frame) -> None:
    """Write this worker's process id to the file ``job``, then sleep far longer than the test waits."""
    Path(job).write_text(str(os.getpid()))
    time.sleep(120)


def _running(pid: int) -> bool:
    """Whether process ``pid`` exists and has not ended (a zombie nobody reaped has ended)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state not in ("Z", "X")


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads process states from /proc (Linux)")
def test_workers_end_with_a_parent_stopped_by_a_signal(tmp_path):
    jobs = [str(tmp_path / "a.pid"), str(tmp_path / "b.pid")]
    driver = (
        "from test_pool import sleep_and_report\n"
        "from affnerf.data.pool import run_jobs\n"
        f"list(run_jobs(sleep_and_report, {jobs!r}, 2, lambda n: None))\n"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).parent), *sys.path])}
    parent = subprocess.Popen([sys.executable, "-c", driver], env=env)
    try:
        deadline = time.monotonic() + 120
        while not all(Path(job).exists() and Path(job).read_text() for job in jobs):
            assert time.monotonic() < deadline and parent.poll() is None, "the workers did not start"
            time.sleep(0.2)
        pids = [int(Path(job).read_text()) for job in jobs]
        parent.send_signal(signal.SIGTERM)  # no cleanup runs in the parent
        parent.wait(timeout=30)
        deadline = time.monotonic() + 20
        while any(_running(pid) for pid in pids) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not any(_running(pid) for pid in pids)
    finally:
        parent.kill()
