"""The worker side of a batch: one decode setup per process (calibrated once), and run_job."""

from __future__ import annotations

import contextlib
import json
import os
import time
import warnings

from ..errors import LfprocError
from ._jobs import Job, JobResult, file_stamp
from ._signals import Cancelled

#: per process: setup key -> DecodeSetup (the calibrated grid and white image), oldest first
_SETUP_CACHE: dict = {}
_GRID_SEEDS: dict = {}  # setup key -> LensGrid fitted by the parent process (see seed_grids)
_SETUP_CACHE_SIZE = 4


def setup_key(job: Job) -> tuple:
    """What a decode setup depends on. The grid and white files' sizes and times are part of it, so a
    long-lived Dask worker recalibrates when the white image or grid file is replaced."""
    return (job.camera_toml, job.calib, job.white, job.decode_interpolation, job.demosaic, job.white_is_white,
            json.dumps([file_stamp(job.calib), file_stamp(job.white), file_stamp(job.dark)]))


def decode_setup(job: Job):
    """The :class:`lfproc.api.DecodeSetup` of a job (:func:`lfproc.prepare_decoding`): one calibration per
    process, reused for all its captures (and handed to local pool processes ready-made, see :func:`run_local`)."""
    key = setup_key(job)
    setup = _SETUP_CACHE.get(key)
    if setup is None:
        from ..api import prepare_decoding
        from ..camera import Camera

        camera = Camera.from_toml_string(job.camera_toml, source="batch camera")
        setup = prepare_decoding(camera, job.white, _GRID_SEEDS.get(key) or job.calib, job.dark,
                                 decode_interpolation=job.decode_interpolation, demosaic=job.demosaic, cache=True,
                                 white_is_white=job.white_is_white)
        if job.camera_path is not None:   # the camera file, by its path (the job carries its text)
            import dataclasses
            setup = dataclasses.replace(setup, inputs={**setup.inputs, "camera": job.camera_path})
        while len(_SETUP_CACHE) >= _SETUP_CACHE_SIZE:
            _SETUP_CACHE.pop(next(iter(_SETUP_CACHE)))
        _SETUP_CACHE[key] = setup
    return setup


def seed_grids(grids: dict) -> None:
    """Grids calibrated by the process that started the batch, keyed by :func:`setup_key`: a Dask
    worker builds its setups from them instead of calibrating the white image again."""
    _GRID_SEEDS.update(grids)


def _portable_setups(jobs: list[Job]) -> dict:
    """This process's setups for ``jobs``, without their per-shape decoders (cheap to rebuild), to pickle."""
    import dataclasses

    keys = {setup_key(job) for job in jobs}
    return {key: dataclasses.replace(setup, _decoders={}) for key, setup in _SETUP_CACHE.items() if key in keys}


def shared_operators(job: Job, progress=None):
    """The deconvolution operators of a batch, built ONCE, in the process that starts it, from its first
    capture (:func:`lfproc.prepare_deconvolution`, through lfproc's cache as ``lfproc deconvolve`` does), to be
    given to every worker (:func:`run_local`, :func:`run_dask`): no worker builds them."""
    from ..api import prepare_deconvolution
    from ..lightfield import LightField, is_lightfield_file

    lf = LightField.load(job.source) if is_lightfield_file(job.source) else decode_setup(job).decode(job.source)
    if lf.camera is None:
        raise LfprocError(f"{job.source}: this light field carries no camera; decode it with `camera=`")
    return prepare_deconvolution(lf, job.deconvolve["z_um"], job.deconvolve["superres"], cache=True,
                                 progress=progress)


def run_job(job: Job, before_commit=None, checkpoint=None, operators=None) -> JobResult:
    """Process one capture; any error becomes a ``failed`` result (with its message), never an exception, and
    every :class:`lfproc.LfprocWarning` it raises is in the result's ``warnings`` (each distinct one once); both
    with their arguments marked (``error.marked``, :mod:`lfproc.errors`), for the command to word.

    The capture's outputs appear together or not at all (:func:`lfproc.atomic.all_or_nothing`):
    ``before_commit()`` runs when all are written, before the first is renamed into place, and may
    raise :class:`Cancelled` to abandon them (the batch was interrupted); that gives a ``cancelled``
    result. ``checkpoint()`` runs before each output file is begun and may raise it too. Errors other than :class:`LfprocError` are bugs, reported as such in the message; catching
    them here keeps one bad capture from stopping a batch of thousands. ``KeyboardInterrupt`` propagates.
    ``operators``: the batch's deconvolution operators (:func:`shared_operators`), which a job with
    ``deconvolve`` needs (it never builds them itself).
    """
    from ..api import deconvolve, focal_stack, view_stack
    from ..atomic import all_or_nothing
    from ..lightfield import LightField, is_lightfield_file

    start = time.perf_counter()
    said = []
    try:
        with all_or_nothing(before_commit, checkpoint), _warnings_into(said):
            lf = LightField.load(job.source) if is_lightfield_file(job.source) else decode_setup(job).decode(job.source)
            if lf.camera is None:
                raise LfprocError(f"{job.source}: this light field carries no camera; decode it with `camera=`")
            outputs = []
            if job.deconvolve:
                if operators is None:
                    raise LfprocError(f"{job.source}: a deconvolution job needs the batch's operators=, built once "
                                      f"(lfproc.batch.shared_operators)")
                volume = deconvolve(lf, **job.deconvolve, operators=operators)
                outputs += volume.save(job.outdir, job.stem)
            if job.refocus_a:
                stack = focal_stack(lf, a=list(job.refocus_a), aperture=job.aperture,
                                    interpolation=job.interpolation, upsample=job.upsample)
                outputs += stack.save(job.outdir, job.stem, format=job.fmt, stack=job.stack)
            if job.views:
                outputs += view_stack(lf, inside_aperture=job.inside_aperture).save(
                    job.outdir, job.stem, format=job.fmt, mosaic=job.mosaic, gif=job.gif)
        return JobResult(job.source, "done", tuple(outputs), None, time.perf_counter() - start, tuple(said))
    except Cancelled:
        return JobResult(job.source, "cancelled", (), None, time.perf_counter() - start, tuple(said))
    except LfprocError as exc:
        return JobResult(job.source, "failed", (), exc.marked, time.perf_counter() - start, tuple(said))
    except Exception as exc:  # noqa: BLE001 - isolate the failure, name it as a bug
        return JobResult(job.source, "failed", (), f"{job.source}: unexpected {type(exc).__name__}: {exc} "
                                                   f"(a bug in lfproc; please report it)",
                         time.perf_counter() - start, tuple(said))


@contextlib.contextmanager
def _warnings_into(said: list):
    """Every :class:`lfproc.LfprocWarning` raised inside is appended to ``said`` (each distinct message once), not
    shown; other warnings go on to the usual handler."""
    from ..errors import LfprocWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        finally:
            others = []
            for item in caught:
                if issubclass(item.category, LfprocWarning):
                    if item.message.marked not in said:
                        said.append(item.message.marked)
                else:
                    others.append(item)
    for item in others:
        warnings.warn_explicit(item.message, item.category, item.filename, item.lineno)


def worker_threads(workers: int) -> int:
    """Threads for each of ``workers`` pool processes: the CPUs this process may use, shared out (at least 1),
    so that the workers' OpenCV and numba threads together do not outnumber the cores."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        cpus = os.cpu_count() or 1
    return max(1, cpus // max(1, workers))


def init_pool_worker(setups: dict | None = None, threads: int = 1) -> None:
    """Set up a local pool process: the parent's decode setups (no second calibration), ``threads`` threads
    for numba and OpenCV (:func:`worker_threads`: parallelism comes mostly from the processes)."""
    _SETUP_CACHE.update(setups or {})
    os.environ.setdefault("NUMBA_NUM_THREADS", str(threads))  # read when numba is first imported, later in run_job
    try:
        import cv2
        cv2.setNumThreads(threads)
    except ImportError:  # pragma: no cover
        pass
