"""Running jobs on a dask.distributed cluster."""

from __future__ import annotations

import uuid

from ..errors import LfprocError
from ._jobs import Job, JobResult
from ._worker import _SETUP_CACHE, run_job, seed_grids, setup_key


def run_dask(jobs: list[Job], scheduler, on_result) -> None:
    """Run one task per capture on a dask.distributed cluster; ``on_result`` is called as tasks finish.

    ``scheduler`` is an address (``tcp://host:8786``) or a ``distributed.Client``. Tasks carry only
    the small :class:`Job` records; workers read captures and write outputs themselves, on a file
    system shared with this machine. A task lost with its worker is rerun elsewhere by the scheduler
    (up to its ``distributed.scheduler.allowed-failures`` times, then reported as failed here).
    """
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise LfprocError("--scheduler needs dask.distributed: pip install 'lfproc[distributed]'") from None
    owns_client = isinstance(scheduler, str)
    if owns_client:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise LfprocError(f"--scheduler {scheduler}: cannot reach the Dask scheduler ({exc}); start it with "
                              f"'dask scheduler' and check the address") from None
    else:
        client = scheduler
    futures = []
    try:
        keys = {setup_key(job) for job in jobs}
        grids = {key: setup.grid for key, setup in _SETUP_CACHE.items() if key in keys}
        if grids:  # the workers there now skip the calibration; any that join later calibrate themselves
            client.run(seed_grids, grids)
        by_key = {}
        for job in jobs:
            # a unique key: two batches of one capture into different OUTDIRs must not share a task
            future = client.submit(run_job, job, key=f"lfproc-{uuid.uuid4().hex}")
            by_key[future.key] = job
            futures.append(future)
        for future in as_completed(futures):
            job = by_key[future.key]
            try:
                result = future.result()
            except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the task took down workers repeatedly
                result = JobResult(job.source, "failed", (), f"{job.source}: the task failed on the cluster: "
                                                             f"{type(exc).__name__}: {exc}")
            on_result(job, result)
    finally:
        if owns_client:
            client.close()
        else:
            client.cancel(futures)

