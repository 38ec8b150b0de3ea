"""Running jobs in a local process pool, isolating a capture that kills its worker."""

from __future__ import annotations

from collections import deque

from ._jobs import Job, JobResult
from ._worker import _portable_setups, init_pool_worker, run_job


def run_local(jobs: list[Job], workers: int, on_result, max_attempts: int = 3) -> None:
    """Run jobs in ``workers`` processes (in this process if 1), calling ``on_result(job, result)`` as each ends.

    Each pool process starts with this process's decode setups for the jobs (see :func:`decode_setup`),
    so the white image is calibrated once, not once per process. At most ``workers`` captures are in
    flight, which bounds memory. A worker process that dies (out of memory, killed) breaks the pool:
    the captures then in flight are suspects and are retried one at a time in the next pool (so a
    capture that kills its worker cannot take others down with it), up to ``max_attempts`` in all,
    then reported as failed; captures not yet started are not charged.

    On ``KeyboardInterrupt`` no new capture starts; those in progress finish (the pool processes
    ignore Ctrl-C) and are reported, then the interrupt propagates.
    """
    if workers <= 1:
        for job in jobs:
            on_result(job, run_job(job))
        return
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    queue = deque(jobs)
    attempts = {job.source: 0 for job in jobs}
    context = multiprocessing.get_context("spawn")  # no fork of numba/OpenCV thread pools
    setups = _portable_setups(jobs)  # calibrated here already (the CLI checks the setup before it starts)

    def collect(future, job, suspects):
        try:
            result = future.result()
        except BrokenProcessPool:
            suspects.append(job)
            return
        on_result(job, result)

    def can_submit(queue, in_flight) -> bool:
        """A free slot, and no suspect involved: a suspect runs alone, in an otherwise idle pool."""
        if not queue or len(in_flight) >= workers or any(attempts[j.source] for j in in_flight.values()):
            return False
        return not (in_flight and attempts[queue[0].source])

    while queue:
        suspects = []
        with ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=init_pool_worker,
                                 initargs=(setups,)) as pool:
            in_flight = {}
            try:
                while queue or in_flight:
                    while can_submit(queue, in_flight):
                        job = queue.popleft()
                        in_flight[pool.submit(run_job, job)] = job
                    done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
                    for future in done:
                        collect(future, in_flight.pop(future), suspects)
                    if suspects:
                        break
            except KeyboardInterrupt:
                for future in wait(in_flight).done:  # the captures in progress finish and are recorded
                    collect(future, in_flight.pop(future), [])
                raise
            for future in wait(in_flight).done:  # the broken pool fails the rest at once
                collect(future, in_flight.pop(future), suspects)
        for job in reversed(suspects):
            attempts[job.source] += 1
            if attempts[job.source] >= max_attempts:
                on_result(job, JobResult(job.source, "failed", (), f"{job.source}: the worker process died "
                                                                   f"{attempts[job.source]} times (out of "
                                                                   f"memory?); try fewer --workers"))
            else:
                queue.appendleft(job)

