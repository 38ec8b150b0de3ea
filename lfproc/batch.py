"""Batch processing: many captures, in parallel, resumable, locally or on a Dask cluster.

A batch is a list of :class:`Job` — plain, picklable data: one capture and what to make of it. The
same :func:`run_job` runs in this process, in a local process pool (:func:`run_local`) or on
dask.distributed workers (:func:`run_dask`); each worker reads its capture and writes its outputs
itself, atomically (:mod:`lfproc.atomic`), so no capture's pixels cross a process boundary (only the
calibrated white image, once per local worker process) and no reader ever sees a half-written file.

The manifest ``OUTDIR/lfproc-manifest.json`` (:class:`Manifest`) records, per capture, a fingerprint
(the capture file's size and modification time, those of the white image and grid file, the camera
file's text, the lfproc version and every parameter that shapes the outputs), the parameters, the
outputs (names relative to OUTDIR), status and error. A rerun skips captures whose fingerprint matches
a ``done`` entry whose outputs and sidecars all still exist, and redoes the rest. The manifest is
rewritten atomically as results arrive (at most every :data:`MANIFEST_SAVE_INTERVAL_S` seconds, and
always at the end or on interruption), so an interrupted batch resumes where it stopped: at worst the
captures of the last few seconds are redone, overwriting their complete outputs with identical ones.

One batch at a time may write to an OUTDIR: :func:`lock_outdir` holds an advisory lock on
``OUTDIR/.lfproc-batch.lock`` for the duration of a run.
"""

from __future__ import annotations

import contextlib
import glob
import hashlib
import json
import os
import time
import uuid
from collections import deque
from dataclasses import dataclass, fields

from .atomic import write_json_atomic
from .errors import LfprocError
from .io import sidecar_path

MANIFEST_NAME = "lfproc-manifest.json"
MANIFEST_VERSION = 1
LOCK_NAME = ".lfproc-batch.lock"
#: at most one manifest write per this many seconds while results arrive (plus one at the end)
MANIFEST_SAVE_INTERVAL_S = 2.0
#: image extensions a folder input is searched for (case-insensitive)
CAPTURE_EXTENSIONS = (".dng", ".cr2", ".cr3", ".nef", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw",
                      ".tif", ".tiff", ".png", ".exr", ".lfr")
#: Job fields that are not parameters of the outputs (where they go, and the camera file's text,
#: which the fingerprint hashes separately)
_NOT_PARAMETERS = ("source", "stem", "outdir", "camera_toml")


@dataclass(frozen=True)
class Job:
    """One capture to process; every field is plain data so it pickles cheaply to any worker.

    Paths are absolute: a worker on another machine resolves them on the shared file system.
    """

    source: str                 # the capture
    stem: str                   # output name prefix
    outdir: str                 # output folder
    camera_toml: str            # the camera file's text
    calib: str | None           # GRID.json (from lfproc calibrate) or None
    white: str | None           # white image or None
    refocus_a: tuple            # refocus parameters a (empty: no refocusing)
    views: bool                 # write the viewpoint images
    fmt: str = "tiff"
    interpolation: str = "linear"
    decode_interpolation: str = "linear"
    demosaic: str = "fast"

    def parameters(self) -> dict:
        """The parameters that shape this capture's outputs, as recorded in the manifest."""
        return {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else v)
                for f in fields(self) if f.name not in _NOT_PARAMETERS}

    def fingerprint(self) -> str:
        """Changes whenever the capture, the camera, the white image, the grid file, lfproc's version or
        any parameter that shapes the outputs changes (not when OUTDIR moves)."""
        from . import __version__

        payload = json.dumps([__version__, self.source, self.stem, self.camera_toml, self.parameters(),
                              [file_stamp(p) for p in (self.source, self.calib, self.white)]],
                             sort_keys=True, default=str)
        return hashlib.sha256(payload.encode()).hexdigest()[:32]


@dataclass(frozen=True)
class JobResult:
    """What became of one capture: ``outputs`` are image paths (each with its sidecar ``NAME.json``)."""

    source: str
    status: str                 # "done" | "failed" | "skipped"
    outputs: tuple = ()
    error: str | None = None
    seconds: float = 0.0


def file_stamp(path: str | None) -> list | None:
    """``[path, size, mtime_ns]`` of a file (size and time None if it is missing), or None for no path."""
    if path is None:
        return None
    try:
        st = os.stat(path)
        return [path, st.st_size, st.st_mtime_ns]
    except OSError:
        return [path, None, None]


def expand_inputs(inputs: list[str]) -> list[str]:
    """Files, folders (their capture files, sorted by name) and glob patterns (sorted matches) → absolute
    paths in the order given, without duplicates."""
    found = []
    for item in inputs:
        if os.path.isdir(item):
            names = sorted(os.listdir(item))
            found += [os.path.join(item, n) for n in names
                      if n.lower().endswith(CAPTURE_EXTENSIONS) and os.path.isfile(os.path.join(item, n))]
        elif any(ch in item for ch in "*?["):
            matches = sorted(glob.glob(item))
            if not matches:
                raise LfprocError(f"{item}: the pattern matches no file; check the pattern")
            found += [m for m in matches if os.path.isfile(m)]
        elif os.path.isfile(item):
            found.append(item)
        else:
            raise LfprocError(f"{item}: no such file or folder; give capture files, folders or glob patterns")
    unique = list(dict.fromkeys(os.path.abspath(p) for p in found))
    if not unique:
        raise LfprocError(f"no captures found in {' '.join(inputs)}; folders are searched for "
                          f"{', '.join(CAPTURE_EXTENSIONS)}")
    return unique


# ------------------------------------------------------------------------------ the worker side
#: per process: setup key -> DecodeSetup (the calibrated grid and white image), oldest first
_SETUP_CACHE: dict = {}
_GRID_SEEDS: dict = {}  # setup key -> LensGrid fitted by the parent process (see seed_grids)
_SETUP_CACHE_SIZE = 4


def setup_key(job: Job) -> tuple:
    """What a decode setup depends on. The grid and white files' sizes and times are part of it, so a
    long-lived Dask worker recalibrates when the white image or grid file is replaced."""
    return (job.camera_toml, job.calib, job.white, job.decode_interpolation, job.demosaic,
            json.dumps([file_stamp(job.calib), file_stamp(job.white)]))


def decode_setup(job: Job):
    """The :class:`lfproc.pipeline.DecodeSetup` of a job: one calibration per process, reused for all its
    captures (and handed to local pool processes ready-made, see :func:`run_local`)."""
    key = setup_key(job)
    setup = _SETUP_CACHE.get(key)
    if setup is None:
        from .camera import Camera
        from .pipeline import prepare_decoding

        camera = Camera.from_toml_string(job.camera_toml, source="batch camera")
        setup = prepare_decoding(camera, job.calib, job.white, interpolation=job.decode_interpolation,
                                 demosaic_method=job.demosaic, grid=_GRID_SEEDS.get(key))
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


def run_job(job: Job) -> JobResult:
    """Process one capture; any error becomes a ``failed`` result (with its message), never an exception.

    Errors other than :class:`LfprocError` are bugs, reported as such in the message; catching them
    here keeps one bad capture from stopping a batch of thousands. ``KeyboardInterrupt`` propagates.
    """
    from .outputs import write_slices, write_views
    from .pipeline import load_lightfield

    start = time.perf_counter()
    try:
        setup = decode_setup(job)
        lf = load_lightfield(job.source, setup)
        outputs = []
        if job.refocus_a:
            from .refocus import refocus

            stack = refocus(lf, list(job.refocus_a), interpolation=job.interpolation)
            outputs += write_slices(job.outdir, job.stem, job.source, setup.camera, job.refocus_a, stack, job.fmt)
        if job.views:
            outputs += write_views(job.outdir, job.stem, job.source, setup.camera, lf.views, job.fmt)
        return JobResult(job.source, "done", tuple(outputs), None, time.perf_counter() - start)
    except LfprocError as exc:
        return JobResult(job.source, "failed", (), str(exc), time.perf_counter() - start)
    except Exception as exc:  # noqa: BLE001 - isolate the failure, name it as a bug
        return JobResult(job.source, "failed", (), f"{job.source}: unexpected {type(exc).__name__}: {exc} "
                                                   f"(a bug in lfproc; please report it)",
                         time.perf_counter() - start)


def init_pool_worker(setups: dict | None = None) -> None:
    """Set up a local pool process: the parent's decode setups (no second calibration), one thread for
    numba and OpenCV (parallelism comes from the processes), and Ctrl-C left to the parent, which lets
    the captures in progress finish."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _SETUP_CACHE.update(setups or {})
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # read when numba is first imported, later in run_job
    try:
        import cv2
        cv2.setNumThreads(1)
    except ImportError:  # pragma: no cover
        pass


# ------------------------------------------------------------------------------ the manifest
def read_manifest(outdir: str) -> dict:
    path = os.path.join(outdir, MANIFEST_NAME)
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except FileNotFoundError:
        return {"version": MANIFEST_VERSION, "captures": {}}
    except (OSError, ValueError) as exc:
        raise LfprocError(f"{path}: unreadable manifest ({exc}); delete it to reprocess everything") from None
    if not isinstance(data, dict) or data.get("version") != MANIFEST_VERSION \
            or not isinstance(data.get("captures"), dict):
        raise LfprocError(f"{path}: not a manifest of this lfproc version; delete it to reprocess everything")
    return data


class Manifest:
    """The manifest of one output folder: read at start, updated as results arrive, saved atomically.

    Layout (JSON)::

        {"version": 1,
         "parameters": {...the last run's command-line parameters...},
         "captures": {"/abs/capture.png": {"status": "done" | "failed", "last_run": "done" | "failed" | "skipped",
                                           "fingerprint": "…", "parameters": {...}, "outputs": ["NAME.tif", …],
                                           "error": null | "message", "seconds": 1.234}},
         "summary": {"done": 0, "skipped": 0, "failed": 0, "total": 0, "seconds": 0.0, "interrupted": false,
                     "failed_captures": [{"source": "…", "error": "…"}]}}

    ``outputs`` are image names relative to OUTDIR; each has its sidecar ``NAME.json`` beside it.
    """

    def __init__(self, outdir: str, parameters: dict, save_interval_s: float = MANIFEST_SAVE_INTERVAL_S):
        self.outdir = outdir
        self.path = os.path.join(outdir, MANIFEST_NAME)
        self.data = read_manifest(outdir)
        self.data["parameters"] = parameters
        self.save_interval_s = save_interval_s
        self._last_save = -float("inf")

    def entry(self, source: str) -> dict | None:
        return self.data["captures"].get(source)

    def is_complete(self, job: Job, fingerprint: str) -> bool:
        """True when ``job`` needs no rerun: same fingerprint, done, every output and sidecar still there."""
        entry = self.entry(job.source)
        if not (entry and entry.get("fingerprint") == fingerprint and entry.get("status") == "done"):
            return False
        images = [os.path.join(self.outdir, name) for name in entry.get("outputs", [])]
        return all(os.path.isfile(p) and os.path.isfile(sidecar_path(p)) for p in images)

    def record(self, job: Job, result: JobResult, fingerprint: str) -> None:
        """Note one capture's result (saved by the next :meth:`save_soon` or :meth:`save`)."""
        if result.status == "skipped":
            self.data["captures"][job.source]["last_run"] = "skipped"
            return
        self.data["captures"][job.source] = {
            "status": result.status, "last_run": result.status, "fingerprint": fingerprint,
            "parameters": job.parameters(),
            "outputs": [os.path.relpath(p, self.outdir) for p in result.outputs],
            "error": result.error, "seconds": round(result.seconds, 3)}

    def save_soon(self) -> None:
        """Save unless the last save was less than ``save_interval_s`` ago."""
        if time.monotonic() - self._last_save >= self.save_interval_s:
            self.save()

    def save(self, summary: dict | None = None) -> None:
        if summary is not None:
            self.data["summary"] = summary
        self.data["captures"] = dict(sorted(self.data["captures"].items()))  # the same order on every run
        write_json_atomic(self.path, self.data)
        self._last_save = time.monotonic()


@contextlib.contextmanager
def lock_outdir(outdir: str):
    """Hold an advisory lock on OUTDIR for one batch run (released when the process ends, however)."""
    import fcntl

    path = os.path.join(outdir, LOCK_NAME)
    try:
        fh = open(path, "a+", encoding="utf-8")
    except OSError as exc:
        raise LfprocError(f"{outdir}: cannot write in the output folder ({exc.strerror}); check -o OUTDIR") from None
    with fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise LfprocError(f"{outdir}: another lfproc batch is writing to this folder; wait for it to finish "
                              f"or choose another -o OUTDIR") from None
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def remove_stale_partial_files(outdir: str) -> list[str]:
    """Delete the temporary files of :func:`lfproc.atomic.atomic_path` that a killed run left in OUTDIR.

    Only called while holding :func:`lock_outdir`, so no other batch is writing them.
    """
    removed = []
    for path in glob.glob(os.path.join(glob.escape(outdir), ".*.part*")):
        if os.path.isfile(path):
            with contextlib.suppress(FileNotFoundError):
                os.remove(path)
                removed.append(path)
    return removed


# ------------------------------------------------------------------------------ executors
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


def available_memory_bytes() -> float:
    """Memory available to new processes: Linux's MemAvailable, else free pages, else 8 GB."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover
        return 8e9


def default_workers(sample_path: str | None, memory_fraction: float = 0.5) -> int:
    """Processes that fit: at most the cores, and at most ``memory_fraction`` of the available memory.

    A worker process peaks at about :data:`PROCESS_BASE_BYTES` plus :data:`BYTES_PER_SENSOR_PIXEL` bytes
    per sensor pixel (the white image read, demosaiced and calibrated in float32, its decoded views,
    then each capture's sensor image, views and refocused stack). The pixel count comes from the first
    capture's header when OpenImageIO can read it, else a 40-megapixel sensor is assumed.
    """
    cores = os.cpu_count() or 1
    pixels = 40e6
    if sample_path is not None:
        with contextlib.suppress(Exception):  # the estimate only sizes the pool
            import OpenImageIO as oiio

            inp = oiio.ImageInput.open(sample_path)
            if inp:
                spec = inp.spec()
                pixels = float(spec.width * spec.height)
                inp.close()
    per_process = PROCESS_BASE_BYTES + pixels * BYTES_PER_SENSOR_PIXEL
    return max(1, min(cores, int(memory_fraction * available_memory_bytes() // per_process)))


#: peak bytes per sensor pixel of a worker process (see default_workers). Measured peak resident memory of
#: one worker, reached while calibrating the white image: 290 MB at 0.5 megapixels (the bundled sample),
#: 585 MB at 4.3 megapixels (the same camera), i.e. 250 MB + 77 bytes per pixel; rounded up for margin.
BYTES_PER_SENSOR_PIXEL = 100
#: a worker process's memory before its first capture (Python, numpy, numba, OpenCV, OpenImageIO)
PROCESS_BASE_BYTES = 250e6
