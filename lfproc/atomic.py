"""Atomic file output: write to a temporary file in the destination folder, then rename over the target.

A reader never sees a half-written file, and an interrupted or failed write leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import uuid
from collections.abc import Mapping

import numpy as np

from .errors import LfprocError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None):
    """Yield a temporary path next to ``path``; on success it is renamed to ``path``, on error removed.

    ``suffix`` defaults to the target's extension, so writers that pick a format from the file name
    (OpenImageIO, numpy) still do so.
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if suffix is None:
        suffix = os.path.splitext(path)[1]
    tmp = None
    try:  # everything from the creation on, so an interrupt at any point leaves no temporary file
        try:
            os.makedirs(folder, exist_ok=True)
            tmp = _create_temporary(folder, "." + os.path.basename(path) + ".", ".part" + suffix)
        except OSError as exc:
            raise LfprocError(f"{path}: cannot write there ({exc.strerror or exc}); check the output folder") from None
        yield tmp
        try:
            os.replace(tmp, path)
        except OSError as exc:
            raise LfprocError(f"{path}: cannot write there ({exc.strerror or exc}); check the output path") from None
    except BaseException:
        if tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                os.remove(tmp)
        raise


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
