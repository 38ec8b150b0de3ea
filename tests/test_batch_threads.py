"""Pool workers share the CPUs out: each runs cores / workers threads of OpenCV and numba (at least 1)."""

import os

from lfproc.batch._worker import worker_threads


def test_worker_threads_share_the_cpus_this_process_may_use(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(8)), raising=False)
    assert [worker_threads(w) for w in (1, 2, 3, 8, 16)] == [8, 4, 2, 1, 1]
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    assert worker_threads(2) == 1
