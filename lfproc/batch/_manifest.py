"""The batch manifest (what was done, with fingerprints, for resuming) and the output folder's lock."""

from __future__ import annotations

import contextlib
import glob
import json
import os
import time

from ..atomic import write_json_atomic
from ..errors import LfprocError
from ..io import sidecar_path
from ._jobs import Job, JobResult

MANIFEST_NAME = "lfproc-manifest.json"
MANIFEST_VERSION = 1
LOCK_NAME = ".lfproc-batch.lock"
#: at most one manifest write per this many seconds while results arrive (plus one at the end)
MANIFEST_SAVE_INTERVAL_S = 2.0

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
        """True when ``job`` needs no rerun: same fingerprint, done, every output and sidecar still there
        (animations have no sidecar)."""
        entry = self.entry(job.source)
        if not (entry and entry.get("fingerprint") == fingerprint and entry.get("status") == "done"):
            return False
        images = [os.path.join(self.outdir, name) for name in entry.get("outputs", [])]
        return all(os.path.isfile(p) and (p.endswith(".gif") or os.path.isfile(sidecar_path(p))) for p in images)

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

