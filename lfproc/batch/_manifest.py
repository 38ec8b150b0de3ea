"""The batch manifest (what was done, with fingerprints, for resuming) and the output folder's lock.

Each capture's result is recorded the moment it arrives, by appending one line to the journal
``OUTDIR/.lfproc-manifest.journal`` (one ``write`` of one JSON line, O_APPEND: a line is there whole or,
after a crash in the middle of it, is ignored). The manifest itself is rewritten atomically from time
to time and at the end, which folds the journal in and removes it; reading a manifest replays any
journal a killed run left. So a capture whose result arrived is never redone, however the run ends.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import json
import os
import time

from ..atomic import json_safe, write_json_atomic
from ..errors import LfprocError
from ..io import sidecar_path
from ._jobs import Job, JobResult

MANIFEST_NAME = "lfproc-manifest.json"
MANIFEST_VERSION = 1
LOCK_NAME = ".lfproc-batch.lock"
#: at most one manifest write per this many seconds while results arrive (plus one at the end)
MANIFEST_SAVE_INTERVAL_S = 60.0
JOURNAL_NAME = ".lfproc-manifest.journal"


def read_manifest(outdir: str) -> dict:
    """The manifest of ``outdir`` with the journal of a run that did not end cleanly replayed into it."""
    path = os.path.join(outdir, MANIFEST_NAME)
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except FileNotFoundError:
        data = {"version": MANIFEST_VERSION, "captures": {}}
    except (OSError, ValueError) as exc:
        raise LfprocError(f"{path}: unreadable manifest ({exc}); delete it to reprocess everything") from None
    if not isinstance(data, dict) or data.get("version") != MANIFEST_VERSION \
            or not isinstance(data.get("captures"), dict):
        raise LfprocError(f"{path}: not a manifest of this lfproc version; delete it to reprocess everything")
    for source, entry in _journal_entries(os.path.join(outdir, JOURNAL_NAME)):
        data["captures"][source] = entry
    return data


def _journal_entries(path: str):
    """(source, entry) of each whole line of a journal; a torn or foreign line is skipped (its capture is redone)."""
    try:
        with open(path, "rb") as fh:
            lines = fh.read().split(b"\n")
    except FileNotFoundError:
        return
    except OSError as exc:
        raise LfprocError(f"{path}: unreadable journal ({exc.strerror}); delete it to redo the captures it "
                          f"records") from None
    for line in lines:
        try:
            item = json.loads(line)
        except ValueError:
            continue
        if isinstance(item, list) and len(item) == 2 and isinstance(item[0], str) and isinstance(item[1], dict):
            yield item[0], item[1]


def has_sidecar(path: str) -> bool:
    """Whether an output comes with a ``NAME.json`` sidecar: every data product does; animations, display
    previews (``NAME_preview.png``/``.jpg``), the focal stack (its slices' records are inside it) and a volume
    (``STEM_volume.ome.tif``, whose record ``STEM_volume.json`` is an output of its own) do not."""
    name = os.path.basename(path).lower()
    return not (name.endswith((".gif", ".json")) or "_preview." in name
                or name.endswith(("_stack.tif", "_stack.ome.tif", "_volume.ome.tif")))


class Manifest:
    """The manifest of one output folder: read at start, updated as results arrive, saved atomically.

    Layout (JSON)::

        {"version": 1,
         "parameters": {...the last run's command-line parameters...},
         "captures": {"/abs/capture.png": {"status": "done" | "failed", "last_run": "done" | "failed" | "skipped",
                                           "fingerprint": "…", "parameters": {...}, "outputs": ["NAME.tif", …],
                                           "error": null | "message", "warnings": ["message", …],
                                           "seconds": 1.234}},
         "summary": {"done": 0, "skipped": 0, "failed": 0, "total": 0, "seconds": 0.0, "interrupted": false,
                     "warned": 0, "failed_captures": [{"source": "…", "error": "…"}]}}

    ``outputs`` are image names relative to OUTDIR; each has its sidecar ``NAME.json`` beside it. ``warnings``
    are the capture's `lfproc.LfprocWarning` messages (each distinct one once; ``[]`` for none); ``warned`` counts
    the captures of the run that had any.
    """

    def __init__(self, outdir: str, parameters: dict, save_interval_s: float = MANIFEST_SAVE_INTERVAL_S):
        self.outdir = outdir
        self.path = os.path.join(outdir, MANIFEST_NAME)
        self.data = read_manifest(outdir)
        self.data["parameters"] = parameters
        self.save_interval_s = save_interval_s
        self.journal = os.path.join(outdir, JOURNAL_NAME)
        self._last_save = time.monotonic()

    def entry(self, source: str) -> dict | None:
        return self.data["captures"].get(source)

    def is_complete(self, job: Job, fingerprint: str) -> bool:
        """True when ``job`` needs no rerun: same fingerprint, done, every output and sidecar still there
        (pictures for people have none: :func:`has_sidecar`)."""
        entry = self.entry(job.source)
        if not (isinstance(entry, dict) and entry.get("fingerprint") == fingerprint and entry.get("status") == "done"):
            return False
        outputs = entry.get("outputs", [])
        if not (isinstance(outputs, list) and all(isinstance(name, str) and name for name in outputs)):
            return False  # an entry edited by hand or damaged: the capture is redone
        images = [os.path.join(self.outdir, name) for name in outputs]
        return all(os.path.isfile(p) and (not has_sidecar(p) or os.path.isfile(sidecar_path(p))) for p in images)

    def record(self, job: Job, result: JobResult, fingerprint: str) -> None:
        """Note one capture's result, durably at once (a line in the journal); :meth:`save` folds it in."""
        if result.status == "skipped":
            self.data["captures"][job.source]["last_run"] = "skipped"
            return
        entry = self.data["captures"][job.source] = {
            "status": result.status, "last_run": result.status, "fingerprint": fingerprint,
            "parameters": job.parameters(),
            "outputs": [os.path.relpath(p, self.outdir) for p in result.outputs],
            "error": result.error, "warnings": list(result.warnings), "seconds": round(result.seconds, 3)}
        line = (json.dumps([job.source, json_safe(entry)], allow_nan=False) + "\n").encode()
        try:
            fd = os.open(self.journal, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
            try:
                if os.write(fd, line) != len(line):
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            finally:
                os.close(fd)
        except OSError as exc:
            raise LfprocError(f"{self.journal}: cannot record {job.source} ({exc.strerror or exc}); free some "
                              f"disk space and rerun to resume") from None

    def save_soon(self) -> None:
        """Save unless the last save was less than ``save_interval_s`` ago (the journal keeps every result)."""
        if time.monotonic() - self._last_save >= self.save_interval_s:
            self.save()

    def save(self, summary: dict | None = None) -> None:
        """Write the whole manifest atomically and drop the journal it now contains."""
        if summary is not None:
            self.data["summary"] = summary
        self.data["captures"] = dict(sorted(self.data["captures"].items()))  # the same order on every run
        write_json_atomic(self.path, self.data)
        with contextlib.suppress(FileNotFoundError):
            os.remove(self.journal)
        self._last_save = time.monotonic()


@contextlib.contextmanager
def lock_outdir(outdir: str):
    """Hold the lock on OUTDIR for one batch run; yields the holder a killed run left (else None).

    ``OUTDIR/.lfproc-batch.lock`` holds an advisory lock (``flock``, released by the system when its
    process ends, however) and names its process (``PID HOST START``); it is removed at the end. A lock
    file whose lock is free was left by a process that is no longer running: it is taken over, and the
    caller says so in one line.
    """
    import fcntl
    import socket

    path = os.path.join(outdir, LOCK_NAME)
    while True:
        try:
            fh = open(path, "a+", encoding="utf-8")
        except OSError as exc:
            raise LfprocError(f"{outdir}: cannot write in the output folder ({exc.strerror}); check `outdir=...`") \
                from None
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.seek(0)
            holder = fh.read().strip()
            fh.close()
            raise LfprocError(f"{outdir}: another batch{_describe_holder(holder)} is writing to this folder; "
                              f"wait for it to finish or choose another `outdir=...`") from None
        try:  # the lock file may have been removed by a batch that ended while this one opened it
            same = os.fstat(fh.fileno()).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        fh.close()
    with fh:
        fh.seek(0)
        stale = fh.read().strip() or None
        fh.seek(0)
        fh.truncate()
        fh.write(f"{os.getpid()} {socket.gethostname()} {time.strftime('%Y-%m-%dT%H:%M:%S')}\n")
        fh.flush()
        try:
            yield None if stale is None else (_describe_holder(stale)[2:-1] or "an earlier run")
        finally:
            with contextlib.suppress(OSError):
                os.remove(path)
            fcntl.flock(fh, fcntl.LOCK_UN)


def _describe_holder(holder: str) -> str:
    """`` (process PID on HOST, since START)`` from a lock file's text, or ``""``."""
    parts = holder.split()
    if len(parts) == 3 and parts[0].isdigit():
        return f" (process {parts[0]} on {parts[1]}, since {parts[2]})"
    return ""


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

