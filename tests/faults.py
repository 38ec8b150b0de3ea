"""Fault injection for the reliability tests: used only by tests, never by lfproc itself.

A spec (a dict; in a subprocess the JSON in ``LFPROC_FAULTS``, installed by ``fault_site/sitecustomize.py``,
which therefore reaches every process lfproc starts, its spawned batch workers included) wraps
``lfproc.io.write_image`` — which every slice and view goes through — to:

- ``announce``: DIR — create ``DIR/STEM`` when a process starts writing capture STEM's outputs;
- ``slow``: {"stems": [...], "seconds": S} — sleep S before each file of those captures;
- ``kill``: {"stem": STEM, "after": N, "marker": PATH} — SIGKILL this process just before its N-th
  file of STEM, once (PATH records the victim's pid, so the retry goes through).

- ``starting``: {"dir": DIR, "seconds": S} — a spawned worker process creates ``DIR/worker-PID`` as soon as
  its interpreter starts, then takes S seconds more to start (the window a Ctrl-C used to hit);
- ``disk_full``: {"folder": DIR, "after": N} — as :func:`disk_full` below, for a whole process.

``disk_full(monkeypatch, folder, after_bytes, errno)`` makes Python-level writes into ``folder`` fail
midway with ``OSError(errno)`` after ``after_bytes`` bytes (builtins.open, which json, Pillow, numpy
and the PLY writer go through).
"""

from __future__ import annotations

import builtins
import errno as errno_module
import json
import os
import signal
import sys
import threading
import time


def install(spec: dict) -> None:
    if spec.get("disk_full"):
        builtins.open = failing_open(spec["disk_full"]["folder"], spec["disk_full"]["after"])
    import lfproc.io as io

    original = getattr(io.write_image, "__wrapped__", io.write_image)
    counts, lock = {}, threading.Lock()

    def write_image(path, *args, **kwargs):
        stem = os.path.basename(os.fspath(path)).split("_")[0]
        with lock:
            counts[stem] = counts.get(stem, 0) + 1
            count = counts[stem]
        if spec.get("announce") and count == 1:
            with open(os.path.join(spec["announce"], stem), "a") as fh:
                fh.write(f"{os.getpid()}\n")
        kill = spec.get("kill")
        if kill and stem == kill["stem"] and count >= kill["after"] and not os.path.exists(kill["marker"]):
            with open(kill["marker"], "w") as fh:
                fh.write(str(os.getpid()))
            os.kill(os.getpid(), signal.SIGKILL)
        slow = spec.get("slow")
        if slow and stem in slow["stems"]:
            time.sleep(slow["seconds"])
        return original(path, *args, **kwargs)

    write_image.__wrapped__ = original
    io.write_image = write_image


def uninstall() -> None:
    import lfproc.io as io

    io.write_image = getattr(io.write_image, "__wrapped__", io.write_image)


def install_from_env() -> None:
    spec = os.environ.get("LFPROC_FAULTS")
    if spec:
        spec = json.loads(spec)
        starting = spec.get("starting")
        if starting and "--multiprocessing-fork" in sys.argv:  # a spawned worker, at its very start
            with open(os.path.join(starting["dir"], f"worker-{os.getpid()}"), "w"):
                pass
            time.sleep(starting["seconds"])
        install(spec)


class _FailingFile:
    """A file object whose writes fail with ``OSError(code)`` once ``budget`` bytes are written."""

    def __init__(self, fh, budget: list, code: int):
        self._fh, self._budget, self._code = fh, budget, code

    def write(self, data):
        size = len(data)
        if size > self._budget[0]:
            self._fh.write(data[: self._budget[0]])  # the disk takes what fits, then refuses
            self._budget[0] = 0
            raise OSError(self._code, os.strerror(self._code))
        self._budget[0] -= size
        return self._fh.write(data)

    def fileno(self):  # no file descriptor: writers that would write to it in C (Pillow) use write() instead
        import io
        raise io.UnsupportedOperation("fileno")

    def __getattr__(self, name):
        return getattr(self._fh, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._fh.close()
        return False

    def __iter__(self):
        return iter(self._fh)


def failing_open(folder, after_bytes: int = 0, code: int = errno_module.ENOSPC):
    """``open`` whose files opened for writing in ``folder`` fail midway (``code``, after ``after_bytes``
    bytes in all); for EACCES the open itself fails."""
    folder = os.path.abspath(os.fspath(folder))
    real_open = builtins.open
    budget = [after_bytes]

    def open_(file, mode="r", *args, **kwargs):
        writing = any(ch in mode for ch in "wax+")
        if writing and isinstance(file, (str, os.PathLike)) and \
                os.path.abspath(os.fspath(file)).startswith(folder + os.sep):
            if code == errno_module.EACCES:
                raise PermissionError(code, os.strerror(code), os.fspath(file))
            return _FailingFile(real_open(file, mode, *args, **kwargs), budget, code)
        return real_open(file, mode, *args, **kwargs)

    return open_


def disk_full(monkeypatch, folder, after_bytes: int = 0, code: int = errno_module.ENOSPC) -> None:
    """From now on (in this test), Python-level writes into ``folder`` fail midway (:func:`failing_open`)."""
    monkeypatch.setattr(builtins, "open", failing_open(folder, after_bytes, code))
