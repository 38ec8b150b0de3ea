"""Atomic file output: write to a temporary file in the destination folder, then rename over the target.

A reader never sees a half-written file, and an interrupted or failed write (a full disk, a lost
permission, Ctrl-C) leaves nothing behind: the temporary file is removed and the error is one
:class:`LfprocError` line naming the target. Inside :func:`all_or_nothing` the renames wait until the
whole group of files is written, so a group (one capture's outputs in a batch) appears together or
not at all.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import threading
import uuid
from collections.abc import Mapping

import numpy as np

from .errors import LfprocError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None):
    """Yield a temporary path next to ``path``; on success it is renamed to ``path``, on error removed.

    ``suffix`` defaults to the target's extension, so writers that pick a format from the file name
    (OpenImageIO, numpy) still do so. An ``OSError`` while writing (ENOSPC, EACCES, EFBIG …) becomes an
    :class:`LfprocError` naming ``path``; the temporary file is gone either way. Inside
    :func:`all_or_nothing` the rename waits for the group's commit.
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if suffix is None:
        suffix = os.path.splitext(path)[1]
    tmp = None
    group = _GROUP
    if group is not None and group.checkpoint is not None:
        group.checkpoint()  # may stop the group (an interrupted batch) before another file starts
    try:  # everything from the creation on, so an interrupt at any point leaves no temporary file
        try:
            os.makedirs(folder, exist_ok=True)
            tmp = _create_temporary(folder, "." + os.path.basename(path) + ".", ".part" + suffix)
        except OSError as exc:
            raise LfprocError(f"{path}: cannot write there ({exc.strerror or exc}); check the output folder") from None
        try:
            yield tmp
        except OSError as exc:
            raise _write_error(path, exc) from None
        if group is not None and group.add(tmp, path):
            tmp = None  # the group renames it at its commit, or removes it
            return
        try:
            os.replace(tmp, path)
        except OSError as exc:
            raise LfprocError(f"{path}: cannot write there ({exc.strerror or exc}); check the output path") from None
    except BaseException:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.remove(tmp)
        raise


def _write_error(path: str, exc: OSError) -> LfprocError:
    """One line naming the file and the likely fix of a write that failed midway."""
    import errno

    hint = {errno.ENOSPC: "free some disk space or choose another output folder",
            errno.EDQUOT: "free some of your disk quota or choose another output folder",
            errno.EFBIG: "the file exceeds the file size limit; choose another output folder",
            errno.EACCES: "check the folder's permissions", errno.EPERM: "check the folder's permissions",
            errno.EROFS: "the file system is read-only; choose another output folder"}.get(exc.errno,
                                                                                        "check the output folder")
    return LfprocError(f"{path}: writing failed ({exc.strerror or exc}); nothing was left behind; {hint}")


class _Group:
    """Temporary files waiting for one rename each at the commit of :func:`all_or_nothing`."""

    def __init__(self, checkpoint=None):
        self.checkpoint = checkpoint
        self.lock = threading.Lock()
        self.pending: list[tuple[str, str]] = []
        self.open = True

    def add(self, tmp: str, path: str) -> bool:
        with self.lock:
            if self.open:
                self.pending.append((tmp, path))
            return self.open

    def close(self) -> list[tuple[str, str]]:
        with self.lock:
            self.open = False
            pending, self.pending = self.pending, []
        return pending


_GROUP: _Group | None = None


@contextlib.contextmanager
def all_or_nothing(before_commit=None, checkpoint=None):
    """Files written atomically inside (by any thread of this process) appear together, at the end.

    Each :func:`atomic_path` keeps its temporary file; when the block ends without an exception,
    ``before_commit()`` is called (it may raise to abandon the group, e.g. when the batch was
    interrupted) and then every file is renamed into place, in the order written. On any exception
    every temporary file is removed and no target changes. ``checkpoint()``, if given, is called
    before each file is begun (and may raise, like ``before_commit``). Not nestable.
    """
    global _GROUP
    if _GROUP is not None:
        raise RuntimeError("all_or_nothing blocks do not nest")
    group = _GROUP = _Group(checkpoint)
    try:
        yield
        if before_commit is not None:
            before_commit()
        pending = group.close()
    except BaseException:
        _GROUP = None
        for tmp, _ in group.close():
            with contextlib.suppress(OSError):
                os.remove(tmp)
        raise
    _GROUP = None
    for i, (tmp, path) in enumerate(pending):
        try:
            os.replace(tmp, path)
        except OSError as exc:
            for rest, _ in pending[i:]:
                with contextlib.suppress(OSError):
                    os.remove(rest)
            raise LfprocError(f"{path}: cannot write there ({exc.strerror or exc}); check the output path") from None


def _create_temporary(folder: str, prefix: str, suffix: str) -> str:
    """Create an empty file with a random name; mode 0666 less the process umask, like any output."""
    for _ in range(100):
        candidate = os.path.join(folder, f"{prefix}{uuid.uuid4().hex[:12]}{suffix}")
        try:
            os.close(os.open(candidate, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            return candidate
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name in {folder}")


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)


def write_json_atomic(path: str | os.PathLike, obj) -> None:
    """Write strict JSON (no NaN/Infinity: use ``None`` for infinite distances) atomically."""
    write_text_atomic(path, json.dumps(json_safe(obj), indent=2, allow_nan=False) + "\n")


def json_safe(obj):
    """A copy of ``obj`` that strict JSON accepts: ±inf -> None, numpy scalars/arrays -> Python.

    NaN is a bug upstream, not a value to hide: it raises ``ValueError``.
    """
    obj = python_scalar(obj)
    if isinstance(obj, float):
        if math.isnan(obj):
            raise ValueError("metadata contains NaN; compute a finite value or None")
        return None if math.isinf(obj) else obj
    if isinstance(obj, Mapping):
        return {str(key): json_safe(value) for key, value in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(value) for value in obj]
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    return obj


def python_scalar(value):
    """numpy scalars and arrays as Python numbers and lists; everything else unchanged."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value
