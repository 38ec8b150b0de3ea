"""Running jobs on a dask.distributed cluster."""

from __future__ import annotations

import contextlib
import uuid

from ..errors import LfprocError
from ._jobs import Job, JobResult
from ._signals import Cancelled, StopSignals
from ._worker import _SETUP_CACHE, run_job, seed_grids, setup_key


def run_dask(jobs: list[Job], scheduler, on_result, operators=None) -> None:
    """Run one task per capture on a dask.distributed cluster; ``on_result`` is called as tasks finish.

    ``scheduler`` is an address (``tcp://host:8786``) or a ``distributed.Client``. Tasks carry only
    the small :class:`Job` records; workers read captures and write outputs themselves, on a file
    system shared with this machine. A task lost with its worker is rerun elsewhere by the scheduler
    (up to its ``distributed.scheduler.allowed-failures`` times, then reported as failed here).
    ``operators`` (the batch's deconvolution operators, :func:`shared_operators`, built once here) are
    scattered to the workers once (``broadcast``): every task of a worker uses its one copy, and a worker
    that joins later receives it from a peer.

    On SIGINT or SIGTERM: the tasks still running are told to abandon their capture at their next
    output file (a ``distributed.Event``: a running task cannot be interrupted), those that finish
    within a grace period are reported, the rest are cancelled; then ``KeyboardInterrupt`` is raised.
    """
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise LfprocError("`scheduler=` needs dask.distributed: pip install 'lfproc[distributed]'") from None
    owns_client = isinstance(scheduler, str)
    if owns_client:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise LfprocError(f"`scheduler={scheduler}`: cannot reach the Dask scheduler ({exc}); start it with "
                              f"'dask scheduler' and check the address") from None
    else:
        client = scheduler
    futures, handled = [], set()
    stop_name = f"lfproc-stop-{uuid.uuid4().hex}"
    with StopSignals() as stop:
        try:
            keys = {setup_key(job) for job in jobs}
            grids = {key: setup.grid for key, setup in _SETUP_CACHE.items() if key in keys}
            if grids:  # the workers there now skip the calibration; any that join later calibrate themselves
                client.run(seed_grids, grids)
            shipped = None if operators is None else client.scatter(operators, broadcast=True, hash=False)
            by_key = {}
            for job in jobs:
                # a unique key: two batches of one capture into different OUTDIRs must not share a task
                future = client.submit(run_job_on_worker, job, stop_name, shipped, key=f"lfproc-{uuid.uuid4().hex}")
                by_key[future.key] = job
                futures.append(future)

            def report(future):
                handled.add(future.key)
                job = by_key[future.key]
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the task took down workers repeatedly
                    result = JobResult(job.source, "failed", (), f"{job.source}: the task failed on the cluster: "
                                                                 f"{type(exc).__name__}: {exc}")
                if result.status != "cancelled":
                    on_result(job, result)

            finished = iter(as_completed(futures))
            while True:
                with stop.interruptible():
                    future = next(finished, None)
                if future is None:
                    break
                report(future)
                stop.check()
        except Cancelled:
            _stop_tasks(client, stop_name, [f for f in futures if f.key not in handled], report)
            raise KeyboardInterrupt from None
        finally:
            if owns_client:
                client.close()
            else:
                client.cancel(futures)


def _stop_tasks(client, stop_name: str, pending: list, report) -> None:
    """Tasks still computing abandon their capture at their commit point (nothing written); those that
    finish within the grace period (renaming their outputs into place) are reported; the rest are cancelled."""
    from distributed import Event, wait

    from ._local import STOP_GRACE_S

    Event(stop_name, client=client).set()
    with contextlib.suppress(Exception):  # a timeout, or the cluster going away
        wait(pending, timeout=STOP_GRACE_S)
    for future in pending:
        if future.status in ("finished", "error"):
            report(future)
    client.cancel(pending, force=True)


def run_job_on_worker(job: Job, stop_name: str, operators=None) -> JobResult:
    """:func:`run_job` on a Dask worker (which cannot interrupt a running task): a capture whose batch was
    stopped is abandoned at its next output file (checked at most every 0.2 s) or before its commit."""
    import time

    from distributed import Event

    last = [time.monotonic()]

    def before_commit():
        if Event(stop_name).is_set():
            raise Cancelled

    def checkpoint():
        if time.monotonic() - last[0] >= 0.2:
            last[0] = time.monotonic()
            before_commit()

    return run_job(job, before_commit=before_commit, checkpoint=checkpoint, operators=operators)
