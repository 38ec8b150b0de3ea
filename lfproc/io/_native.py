"""What the image libraries print themselves: LibRaw, libtiff, libpng and the rest write their own errors to file
descriptor 2 ("Unexpected end of file" before lfproc's one-line message, issue 38). Every call into them runs in
`libraries_quiet`, which routes file descriptor 2 into a buffer for the duration: the text is kept for lfproc's
own message and shown nowhere else.

Threads may call in at once: the first to enter routes descriptor 2, the last to leave restores it, and each
reads back what was written while it was inside. Whatever else the process writes to stderr meanwhile (another
thread's line, while a library reads a file) is in that buffer too, and not shown.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import threading


class CapturedText:
    """What was written to file descriptor 2 inside :func:`libraries_quiet` (available after it ends)."""

    def __init__(self):
        self.value = ""

    def text(self) -> str:
        return self.value


_lock = threading.Lock()
_state = {"users": 0, "saved": None, "sink": None}


@contextlib.contextmanager
def libraries_quiet():
    """File descriptor 2 goes into a buffer while inside; yields a :class:`CapturedText` that holds what was
    written there once the block ends. Where descriptor 2 cannot be routed (closed), the block runs as it is."""
    captured = CapturedText()
    _flush_stderr()
    with _lock:
        try:
            if _state["users"] == 0:
                _state["sink"] = tempfile.TemporaryFile()
                _state["saved"] = os.dup(2)
                os.dup2(_state["sink"].fileno(), 2)
            start = os.lseek(2, 0, os.SEEK_END)
        except OSError:
            start = None
        else:
            _state["users"] += 1
    if start is None:
        yield captured
        return
    try:
        yield captured
    finally:
        _flush_stderr()
        with _lock:
            sink = _state["sink"]
            end = os.lseek(2, 0, os.SEEK_END)
            sink.seek(start)
            captured.value = sink.read(max(0, end - start)).decode("utf-8", "replace")
            _state["users"] -= 1
            if _state["users"] == 0:
                os.dup2(_state["saved"], 2)
                os.close(_state["saved"])
                sink.close()
                _state["saved"] = _state["sink"] = None


def _flush_stderr() -> None:
    """Python's own stderr buffer out to descriptor 2 before it is routed or restored (none in some hosts)."""
    if sys.stderr is not None:
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.flush()
