"""The one exception type a user of lfproc needs to catch, and its warning.

The library words its messages for a Python caller: an argument is named as in a call, ``white=`` (the
argument), ``white=...`` (a value of it), ``aperture=2.8`` (this value) or ``white_is_white=True`` (a
switch), never as a command's flag. The commands reword what they report with their flags
(:mod:`lfproc.cli.words`, one table).
"""

import os
import sys
import warnings

_PACKAGE = os.path.dirname(os.path.abspath(__file__))


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


def warn(message: str, category: type = LfprocWarning) -> None:
    """Warn ``message`` (an :class:`LfprocWarning` unless ``category`` says otherwise) at the caller's line: the
    first frame outside the lfproc package, however deep inside lfproc the warning is raised.

    Parameters
    ----------
    message : str
        One line naming the input and what to do (Python argument names, never flags).
    category : type, optional
        A ``Warning`` subclass (default :class:`LfprocWarning`).

    Returns
    -------
    None
    """
    frame, level = sys._getframe(1), 2   # stacklevel 2: the frame that called warn()
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE + os.sep):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)
