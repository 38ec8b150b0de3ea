"""Errors in Python words: a library call's message names its arguments (``white=``), never the flags of
the commands (``--white WHITE``), which share the checks that raise them."""

from __future__ import annotations

import contextlib
import contextvars
import re

from ..errors import LfprocError

#: command-line flag -> the Python argument of the API that means the same
FLAG_ARGUMENTS = {
    "--white-dir": "white_dir", "--white": "white", "--calib": "grid", "--dark": "dark", "--camera": "camera",
    "--aperture": "aperture", "--z-range": "z_um", "--depth-range": "depth_range_mm", "--a": "a",
    "--at": "distance_mm", "--decode-interpolation": "decode_interpolation", "--demosaic": "demosaic",
    "--interpolation": "interpolation", "--upsample": "upsample", "--min-confidence": "min_confidence",
}

_FLAG = re.compile(r"(?<![\w-])(--[a-z][a-z-]*)(?:[ =]([A-Z][A-Z_.]*|-?[0-9][0-9.eE+-]*(?::[0-9.eE+-]+)*))?")


def python_words(message: str) -> str:
    """``message`` with each command-line flag (and its metavar) replaced by the Python argument
    (``--white WHITE`` → ``white=``, ``--aperture 2`` → ``aperture=2``); quoted commands stay as they are."""
    parts = re.split(r"('[^']*')", message)
    for i in range(0, len(parts), 2):
        parts[i] = _FLAG.sub(_argument, parts[i])
    return "".join(parts)


def _argument(match) -> str:
    flag, value = match.group(1), match.group(2)
    name = FLAG_ARGUMENTS.get(flag)
    if name is None:
        return match.group(0)
    if value is None or value[0].isalpha():
        return f"{name}="
    return f"{name}={value}"


#: True while a command runs the API: its errors keep the flags the command's user typed
_COMMAND = contextvars.ContextVar("lfproc_command_words", default=False)


@contextlib.contextmanager
def command_words():
    """Inside, the API's errors keep the commands' flags (the commands run on the API: their users typed
    ``--white``, not ``white=``)."""
    token = _COMMAND.set(True)
    try:
        yield
    finally:
        _COMMAND.reset(token)


@contextlib.contextmanager
def speaking_python():
    """Re-raise an :class:`LfprocError` from inside with its message in Python words (not inside
    :func:`command_words`)."""
    try:
        yield
    except LfprocError as exc:
        if _COMMAND.get():
            raise
        words = python_words(str(exc))
        if words == str(exc):
            raise
        try:
            replacement = type(exc)(words)
        except TypeError:
            replacement = LfprocError(words)
        raise replacement from None
