"""Batch processing: many captures, in parallel, resumable, locally or on a Dask cluster.

A batch is a list of :class:`Job` — plain, picklable data: one capture and what to make of it. The
same :func:`run_job` runs in a local process pool or on dask.distributed workers; each worker reads
its capture and writes its outputs itself (atomically), so no image crosses the scheduler. The
manifest ``OUTDIR/lfproc-manifest.json`` records every capture's fingerprint (its file's size and
modification time plus every parameter that changes the outputs), outputs, status and error; a
rerun skips captures whose fingerprint matches a completed entry whose outputs all exist, and redoes
the rest. The manifest is rewritten atomically after every capture, so an interrupted batch resumes
where it stopped.
"""

from __future__ import annotations

import functools
import glob
import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass

from .atomic import write_json_atomic
from .errors import LfprocError

MANIFEST_NAME = "lfproc-manifest.json"
MANIFEST_VERSION = 1
#: image extensions a folder input is searched for (case-insensitive)
CAPTURE_EXTENSIONS = (".dng", ".cr2", ".cr3", ".nef", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw",
                      ".tif", ".tiff", ".png", ".exr", ".lfr")


@dataclass(frozen=True)
class Job:
    """One capture to process; every field is plain data so it pickles cheaply to any worker."""

    source: str                 # absolute path of the capture
    stem: str                   # output name prefix
    outdir: str                 # absolute output folder
    camera_toml: str            # the camera file's content
    calib: str | None           # absolute path of GRID.json
    white: str | None           # absolute path of the white image
    refocus_a: tuple            # refocus parameters (empty: no refocusing)
    views: bool                 # write the viewpoint images
    fmt: str = "tiff"
    interpolation: str = "linear"
    decode_interpolation: str = "linear"
    demosaic: str = "fast"

    def fingerprint(self) -> str:
        """Changes whenever the capture file or any parameter that shapes the outputs changes."""
        try:
            st = os.stat(self.source)
            stamp = (st.st_size, st.st_mtime_ns)
        except OSError:
            stamp = None
        aux = []
        for path in (self.calib, self.white):
            try:
                aux.append(None if path is None else (path, os.stat(path).st_size, os.stat(path).st_mtime_ns))
            except OSError:
                aux.append((path, None))
        payload = json.dumps([asdict(self), stamp, aux], sort_keys=True, default=str)
        return hashlib.sha256(payload.encode()).hexdigest()[:32]


@dataclass(frozen=True)
class JobResult:
    source: str
    status: str                 # "done" | "failed" | "skipped"
    outputs: tuple = ()
    error: str | None = None
    seconds: float = 0.0


def expand_inputs(inputs: list[str]) -> list[str]:
    """Files, folders (their capture files, sorted) and glob patterns → sorted absolute paths, no duplicates."""
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
@functools.lru_cache(maxsize=4)
def _decode_setup(camera_toml: str, calib: str | None, white: str | None, decode_interpolation: str,
                  demosaic: str):
    """One calibration and white-image decode per worker process, reused for all its captures."""
    from .camera import Camera
    from .pipeline import prepare_decoding

    camera = Camera.from_toml_string(camera_toml, source="batch camera")
    return prepare_decoding(camera, calib, white, interpolation=decode_interpolation, demosaic_method=demosaic)


def run_job(job: Job) -> JobResult:
    """Process one capture; user errors become a ``failed`` result, never an exception."""
    from .outputs import write_slices, write_views
    from .pipeline import load_lightfield

    start = time.perf_counter()
    try:
        setup = _decode_setup(job.camera_toml, job.calib, job.white, job.decode_interpolation, job.demosaic)
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


def limit_worker_threads() -> None:
    """One thread per worker process for numba and OpenCV: parallelism comes from the processes."""
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
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
    if not isinstance(data, dict) or data.get("version") != MANIFEST_VERSION or "captures" not in data:
        raise LfprocError(f"{path}: not a manifest of this lfproc version; delete it to reprocess everything")
    return data


def is_complete(entry: dict | None, fingerprint: str) -> bool:
    """A manifest entry that needs no rerun: same fingerprint, done, every output still there."""
    return bool(entry and entry.get("fingerprint") == fingerprint and entry.get("status") == "done"
                and all(os.path.exists(p) for p in entry.get("outputs", [])))


class Manifest:
    """The manifest file of one output folder, updated (atomically) after every capture."""

    def __init__(self, outdir: str, parameters: dict):
        self.path = os.path.join(outdir, MANIFEST_NAME)
        self.data = read_manifest(outdir)
        self.data["parameters"] = parameters

    def entry(self, source: str) -> dict | None:
        return self.data["captures"].get(source)

    def record(self, result: JobResult, fingerprint: str) -> None:
        if result.status == "skipped":
            self.data["captures"][result.source]["last_status"] = "skipped"
        else:
            self.data["captures"][result.source] = {
                "fingerprint": fingerprint, "status": result.status, "last_status": result.status,
                "outputs": list(result.outputs), "error": result.error, "seconds": round(result.seconds, 3)}
        self.save()

    def save(self, summary: dict | None = None) -> None:
        if summary is not None:
            self.data["summary"] = summary
        write_json_atomic(self.path, self.data)


# ------------------------------------------------------------------------------ executors
def run_local(jobs: list[Job], workers: int, on_result, max_retries: int = 2) -> None:
    """Run jobs in ``workers`` processes (in this process if 1), calling ``on_result`` as each ends.

    At most ``workers`` captures are in flight, which bounds memory. A worker process that dies (out
    of memory, killed) breaks the pool: the unfinished jobs are retried in a fresh pool, up to
    ``max_retries`` times each, then reported as failed.
    """
    if workers <= 1:
        for job in jobs:
            on_result(job, run_job(job))
        return
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool
    import multiprocessing

    pending = list(jobs)
    attempts = {job.source: 0 for job in jobs}
    context = multiprocessing.get_context("spawn")  # no fork of numba/OpenCV thread pools
    while pending:
        retry = []
        with ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                 initializer=limit_worker_threads) as pool:
            queue = list(pending)
            in_flight = {}
            while queue or in_flight:
                while queue and len(in_flight) < workers:
                    job = queue.pop(0)
                    in_flight[pool.submit(run_job, job)] = job
                done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
                broken = False
                for future in done:
                    job = in_flight.pop(future)
                    try:
                        on_result(job, future.result())
                    except BrokenProcessPool:
                        broken = True
                        retry.append(job)
                if broken:
                    retry += list(in_flight.values()) + queue
                    break
        pending = []
        for job in retry:
            attempts[job.source] += 1
            if attempts[job.source] > max_retries:
                on_result(job, JobResult(job.source, "failed", (), "the worker process died repeatedly "
                                                                   "(out of memory?); try fewer --workers"))
            else:
                pending.append(job)


def run_dask(jobs: list[Job], scheduler: str, on_result, retries: int = 2) -> None:
    """Run one task per capture on a dask.distributed cluster; results arrive as tasks finish.

    Tasks carry only the small :class:`Job` records; workers read captures and write outputs on
    their own file system (shared with this machine for the outputs to be visible here). A task
    lost with its worker is rerun by the scheduler; ``retries`` more attempts follow an exception.
    """
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise LfprocError("--scheduler needs dask.distributed: pip install 'lfproc[distributed]'") from None
    try:
        client = Client(scheduler, timeout="20s") if isinstance(scheduler, str) else scheduler
    except (OSError, TimeoutError) as exc:
        raise LfprocError(f"cannot reach the Dask scheduler at {scheduler} ({exc}); start it with "
                          f"'dask scheduler' and check the address") from None
    owns_client = isinstance(scheduler, str)
    try:
        by_key = {}
        futures = []
        for job in jobs:
            future = client.submit(run_job, job, key=f"lfproc-{job.fingerprint()}", pure=False, retries=retries)
            by_key[future.key] = job
            futures.append(future)
        for future in as_completed(futures):
            job = by_key[future.key]
            try:
                result = future.result()
            except Exception as exc:  # a task that kept failing on the workers (not a user error)
                result = JobResult(job.source, "failed", (), f"task failed on the cluster: {exc!r}")
            on_result(job, result)
    finally:
        if owns_client:
            client.close()


def default_workers(sample_path: str | None, camera) -> int:
    """Processes that fit: at most the cores, and at most half the available memory per capture estimate.

    A capture needs roughly its sensor image in float32 a few times over (read, demosaic, remap) plus
    the decoded views and the white image's views; the estimate uses the file's pixel count when
    it can be read cheaply and otherwise a 40-megapixel sensor.
    """
    cores = os.cpu_count() or 1
    pixels = 40e6
    if sample_path is not None:
        try:
            import OpenImageIO as oiio
            inp = oiio.ImageInput.open(sample_path)
            if inp:
                spec = inp.spec()
                pixels = float(spec.width * spec.height)
                inp.close()
        except Exception:  # noqa: BLE001 - the estimate only sizes the pool
            pass
    per_capture = pixels * 4 * 3 * 6  # bytes
    try:
        available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover
        available = 8e9
    return max(1, min(cores, int(0.5 * available // per_capture)))
