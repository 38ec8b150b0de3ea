"""Running jobs in local worker processes: a dead worker's capture retried, a clean stop on a signal.

Each worker process is started with ``spawn`` (no fork of numba/OpenCV thread pools) and talks to this
process over its own pipe, so the process that runs each capture is known: a worker that dies (out of
memory, killed) costs exactly its capture one attempt, and that capture is retried in a fresh process.

Stopping (Ctrl-C reaches the whole process group; SIGTERM; see :mod:`._signals`): worker processes
ignore SIGINT from their first instruction on (they start with it blocked) and stop on SIGTERM, which
only this process sends them. On a stop this process sends it to every busy worker: a capture still
computing is abandoned (its temporary files removed, nothing of it written), one already renaming its
outputs into place finishes and is reported. Results that arrive are recorded; workers that do not
answer within :data:`STOP_GRACE_S` seconds are killed. Then ``KeyboardInterrupt`` is raised.
"""

from __future__ import annotations

import contextlib
import os
import signal
import time
from collections import deque

from ._jobs import Job, JobResult
from ._signals import Cancelled, StopSignals, signals_blocked
from ._worker import _portable_setups, init_pool_worker, run_job, worker_threads

#: seconds a worker has to answer a stop (a capture that is computing is abandoned at once)
STOP_GRACE_S = 0.5
#: seconds a worker that is renaming a capture's outputs into place has to finish it
COMMIT_GRACE_S = 10.0
#: the message a worker sends when it starts renaming a capture's outputs into place
COMMITTING = "committing"


def run_local(jobs: list[Job], workers: int, on_result, max_attempts: int = 3, operators=None) -> None:
    """Run jobs in ``workers`` processes (in this process if 1), calling ``on_result(job, result)`` as each ends.

    Each worker process starts with this process's decode setups for the jobs (see :func:`decode_setup`),
    so the white image is calibrated once, not once per process, and with ``operators`` (the deconvolution
    operators of the batch, :func:`shared_operators`: built once, here) pickled into it. At most ``workers`` captures are in
    flight, which bounds memory. A capture whose worker process dies is retried alone (nothing else runs
    beside it, in case memory was short) in a fresh process, up to ``max_attempts`` in all, then
    reported as failed; the other captures are not charged.

    Raises ``KeyboardInterrupt`` after a clean stop on SIGINT or SIGTERM (module docstring): every
    capture whose outputs were written has been passed to ``on_result``; the others wrote nothing.
    """
    with StopSignals() as stop:
        if workers <= 1:
            _run_here(jobs, on_result, stop, operators)
        else:
            _run_pool(jobs, workers, on_result, max_attempts, stop, operators)


def _run_here(jobs, on_result, stop: StopSignals, operators=None) -> None:
    for job in jobs:
        try:
            with stop.interruptible():
                result = run_job(job, before_commit=stop.commit_point, operators=operators)
        except Cancelled:
            result = JobResult(job.source, "cancelled")
        if result.status == "cancelled":
            raise KeyboardInterrupt
        on_result(job, result)
        if stop.requested:
            raise KeyboardInterrupt


class _Worker:
    """One worker process, its end of the pipe and the job it runs (None when idle)."""

    def __init__(self, context, setups: dict, threads: int = 1, operators=None):
        self.conn, child = context.Pipe()
        self.process = context.Process(target=_worker_main, args=(child, setups, threads, operators), daemon=True,
                                       name="lfproc-batch-worker")
        with signals_blocked():  # a Ctrl-C to the process group cannot hit its start-up
            self.process.start()
        child.close()
        self.job: Job | None = None
        self.committing = False

    def send(self, job: Job | None) -> bool:
        self.job, self.committing = job, False
        try:
            self.conn.send(job)
            return True
        except OSError:  # it died while idle
            return False

    def receive(self):
        """The job's result, or None while it is still running; raises EOFError if the process died."""
        while self.conn.poll():
            message = self.conn.recv()
            if message == COMMITTING:
                self.committing = True
                continue
            self.job, self.committing = None, False
            return message
        if not self.process.is_alive():
            raise EOFError
        return None

    def end(self, deadline: float) -> None:
        self.process.join(max(0.0, deadline - time.monotonic()))
        if self.process.is_alive():
            self.process.kill()
            self.process.join()
        self.conn.close()


def _run_pool(jobs, workers: int, on_result, max_attempts: int, stop: StopSignals, operators=None) -> None:
    import multiprocessing
    from multiprocessing.connection import wait

    context = multiprocessing.get_context("spawn")
    setups = _portable_setups(jobs)  # calibrated here already (the CLI checks the setup before it starts)
    queue = deque(jobs)
    attempts = {job.source: 0 for job in jobs}
    pool: list[_Worker] = []

    def busy():
        return [w for w in pool if w.job is not None]

    def start_jobs():
        """Fill free slots; a capture whose worker died before runs alone."""
        while queue and len(busy()) < workers and not any(attempts[w.job.source] for w in busy()) \
                and not stop.requested:  # a signal that came while a worker started: start no other
            if busy() and attempts[queue[0].source]:
                return
            worker = next((w for w in pool if w.job is None), None)
            if worker is None:
                worker = _Worker(context, setups, worker_threads(workers), operators)
                pool.append(worker)
            job = queue.popleft()
            if not worker.send(job):
                worker.job = None
                queue.appendleft(job)  # it never started: no attempt charged
                pool.remove(worker)
                worker.end(time.monotonic())

    def collect(worker: _Worker, record: bool = True) -> None:
        job = worker.job
        try:
            result = worker.receive()
        except (EOFError, OSError):
            pool.remove(worker)
            worker.end(time.monotonic())
            if not record:
                return
            attempts[job.source] += 1
            if attempts[job.source] >= max_attempts:
                on_result(job, JobResult(job.source, "failed", (), f"{job.source}: the worker process died "
                                                                   f"{attempts[job.source]} times (out of "
                                                                   f"memory?); try fewer `workers=`"))
            else:
                queue.appendleft(job)
            return
        if result is not None and result.status != "cancelled":
            on_result(job, result)

    try:
        while queue or busy():
            start_jobs()
            running = busy()
            with stop.interruptible():
                wait([w.conn for w in running] + [w.process.sentinel for w in running])
            for worker in running:
                collect(worker)
            stop.check()
    except Cancelled:
        _stop_workers(pool, busy, collect, wait)
        raise KeyboardInterrupt from None
    finally:
        deadline = time.monotonic() + STOP_GRACE_S
        for worker in pool:
            if worker.job is None:
                worker.send(None)
        for worker in pool:
            worker.end(deadline)


def _stop_workers(pool, busy, collect, wait) -> None:
    """SIGTERM the busy workers; record what they finish within the grace periods."""
    for worker in busy():
        with contextlib.suppress(ProcessLookupError):
            os.kill(worker.process.pid, signal.SIGTERM)
    now = time.monotonic()
    deadline, commit_deadline = now + STOP_GRACE_S, now + COMMIT_GRACE_S
    while busy():
        limit = commit_deadline if any(w.committing for w in busy()) else deadline
        timeout = limit - time.monotonic()
        if timeout <= 0:
            break
        running = busy()
        wait([w.conn for w in running] + [w.process.sentinel for w in running], timeout)
        for worker in running:
            collect(worker, record=False)
    for worker in busy():  # not answering: killed; its temporary files are removed by the caller
        worker.process.kill()
        worker.job = None


def _worker_main(conn, setups: dict, threads: int = 1, operators=None) -> None:
    """A worker process: run the jobs the parent sends until it sends None, the pipe closes or SIGTERM."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is for the parent, which stops the workers
    _die_with_parent()
    with StopSignals((signal.SIGTERM,)) as stop:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, (signal.SIGINT, signal.SIGTERM))  # blocked since the start
        try:
            init_pool_worker(setups, threads)
            while not stop.requested:
                with stop.interruptible():
                    job = conn.recv()
                if job is None:
                    return

                def before_commit():
                    stop.commit_point()
                    conn.send(COMMITTING)

                try:
                    with stop.interruptible():
                        result = run_job(job, before_commit=before_commit, operators=operators)
                except Cancelled:
                    result = JobResult(job.source, "cancelled")
                conn.send(result)
        except (Cancelled, EOFError, OSError):  # stopped while idle, or the parent is gone
            return


def _die_with_parent() -> None:
    """Linux: SIGTERM this process when the parent dies (even by SIGKILL), so no worker outlives a batch."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGTERM), 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        pass
    if os.getppid() == 1:  # the parent died before the line above
        os._exit(0)
