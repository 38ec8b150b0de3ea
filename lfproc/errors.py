"""The one exception type a user of lfproc needs to catch, its warning, and errors in Python words.

A library call's message names its arguments (``white=``), never the flags of the commands (``--white
WHITE``), which share the checks that raise them: the Python API and the public functions that share
checks with the commands wrap their work in :func:`speaking_python`; the commands run inside
:func:`command_words`, where messages keep their flags.
"""

import contextlib
import contextvars
import re


class LfprocError(Exception):
    """An error the user caused and can fix: a bad file, an impossible camera, an `a` out of range.

    The message is a single line that names the input and says what to do. The CLI prints it,
    exits with status 2 and leaves no partial output behind.
    """

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


class LfprocWarning(UserWarning):
    """Something the user should know that does not stop the work: an untrustworthy grid fit, slices whose
    border band is less refocused, a decode without devignetting.

    Library calls never print; they warn with this category (``warnings.warn(..., LfprocWarning)``), so a
    notebook can filter them (``warnings.simplefilter("ignore", lfproc.LfprocWarning)``). The commands
    print each as one line on stderr.
    """


#: command-line flag -> the Python argument of the API that means the same
FLAG_ARGUMENTS = {
    "--white-dir": "white_dir", "--white": "white", "--calib": "grid", "--dark": "dark", "--camera": "camera",
    "--aperture": "aperture", "--z-range": "z_um", "--depth-range": "depth_range_mm", "--a": "a",
    "--at": "distance_mm", "--decode-interpolation": "decode_interpolation", "--demosaic": "demosaic",
    "--interpolation": "interpolation", "--upsample": "upsample", "--min-confidence": "min_confidence",
}

_FLAG = re.compile(r"(?<![\w-])(--[a-z][a-z-]*)(?:[ =]([A-Z][A-Z0-9_]*(?:[:.][A-Za-z0-9_]+)*(?:\[[^\]]*\])?(?![\w])"
                   r"|-?[0-9][0-9.eE+-]*(?::[0-9.eE+-]+)*))?")


#: a bare metavar where a message says what to pass -> the Python argument
_METAVARS = re.compile(r"\b(as|pass|give) (WHITE|CAM|DARK|GRID\.json)\b")
_METAVAR_ARGUMENTS = {"WHITE": "white=", "CAM": "camera=", "DARK": "dark=", "GRID.json": "grid="}


def python_words(message: str) -> str:
    """``message`` with each command-line flag (and its metavar) replaced by the Python argument
    (``--white WHITE`` → ``white=``, ``--aperture 2`` → ``aperture=2``); quoted commands stay as they are."""
    parts = re.split(r"('[^']*')", message)
    for i in range(0, len(parts), 2):
        parts[i] = _FLAG.sub(_argument, parts[i])
        parts[i] = _METAVARS.sub(lambda m: f"{m.group(1)} {_METAVAR_ARGUMENTS[m.group(2)]}", parts[i])
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
