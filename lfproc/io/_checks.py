"""Checks every reader shares: the input file exists and is readable; one-line messages."""

from __future__ import annotations

import os

import numpy as np

from ..errors import LfprocError


class _NotThisFormat(Exception):
    """A reader does not recognise the file (another reader may); the message says why."""


def existing_file(path) -> str:
    path = os.fspath(path)
    if not os.path.exists(path):
        raise LfprocError(f"{path}: file not found; check the path")
    if os.path.isdir(path):
        raise LfprocError(f"{path}: is a folder, not an image file; pass a file in it (e.g. {os.path.join(path, '*.tif')})")
    if not os.path.isfile(path):
        raise LfprocError(f"{path}: is not a regular file; pass an image file")
    if os.path.getsize(path) == 0:
        raise LfprocError(f"{path}: file is empty; re-copy or re-export the capture")
    if not os.access(path, os.R_OK):
        raise LfprocError(f"{path}: file is not readable; check its permissions")
    return path


def require_finite_pixels(pixels: np.ndarray, path: str) -> None:
    if not np.all(np.isfinite(pixels)):
        raise LfprocError(f"{path}: the image contains NaN or infinite values; re-export it with finite pixels")


def unreadable_reasons(reasons: list[str]) -> str:
    """`` (why)`` after "not a readable image …": the readers' own messages where one recognised the format
    and found it damaged; nothing where none knows the format (their texts would only name their internals)."""
    unknown = ("could not find a format reader", "not a supported camera raw", "Input/output error",
               "unknown format")
    told = [reason for reason in reasons if not any(text in reason for text in unknown)]
    return f" ({'; '.join(told)})" if told else " (none of lfproc's readers knows its format)"


def one_line(text: str) -> str:
    return " ".join(str(text or "").split())


def library_error(geterror) -> str:
    """A C library's error message (``geterror()`` of OpenImageIO) as one line; its bytes may not be
    UTF-8 when they quote a corrupt file, and that must not become a UnicodeDecodeError."""
    try:
        return one_line(geterror())
    except UnicodeDecodeError:
        return "the library's message is not readable text"


#: an image may decode to at most this many bytes per byte of file (deflate tops out near 1032:1, LZW
#: near 2730:1) plus :data:`MAX_DECODED_SLACK`: a header declaring more is corrupt or hostile
MAX_DECODED_PER_FILE_BYTE = 4096
MAX_DECODED_SLACK = 64 << 20


def check_declared_size(path: str, declared_bytes: int, what: str) -> None:
    """Refuse before allocating when a header declares more data than the file's size can hold."""
    size = os.path.getsize(path)
    if declared_bytes > MAX_DECODED_PER_FILE_BYTE * size + MAX_DECODED_SLACK:
        raise LfprocError(f"{path}: the header declares {what} ({declared_bytes / 1e6:.0f} MB of pixels) that a "
                          f"{size}-byte file cannot hold; the file is corrupt, re-copy or re-export it")
