"""The one exception type a user of lfproc needs to catch, and its warning.

A message marks each argument it names between backticks, as in a call: ``"`white=`"`` (the argument),
``"`white=...`"`` (a value of it), ``"`aperture=2.8`"`` (this value) or ``"`white_is_white=True`"`` (a switch);
and a how-to in Python between backticks too (``"`lfproc.calibrate_white(white, camera).save(path)`"``). A Python
caller reads the message without the backticks (``str(error)``, ``str(warning)``); the commands read
``error.marked`` and word each mark themselves (:mod:`lfproc.cli.words`: an argument becomes the flag of
their option of that name). The library never names a command or a flag.
"""

import os
import re
import sys
import warnings

_PACKAGE = os.path.dirname(os.path.abspath(__file__))

#: a mark: an argument (``name=``, ``name=VALUE``) or a how-to in Python, between backticks
MARK = re.compile(r"`([^`]*)`")
#: an argument inside a mark: its name and the value after ``=`` (``""``, ``"..."``, ``"True"``, a value)
ARGUMENT = re.compile(r"([a-z_][a-z0-9_]*)=(.*)", re.DOTALL)


def python_words(marked: str) -> str:
    """``marked`` as a Python caller reads it: each mark's text, without the backticks."""
    return MARK.sub(r"\1", marked)


def arguments(marked: str) -> list:
    """The argument names ``marked`` names (``["white", "white_dir"]``), in order."""
    found = (ARGUMENT.fullmatch(text) for text in MARK.findall(marked))
    return [match.group(1) for match in found if match]


class LfprocError(Exception):
    """An error the user caused and can fix: a bad file, an impossible camera, an `a` out of range.

    The message is a single line that names the input and says what to do. The CLI prints it,
    exits with status 2 and leaves no partial output behind.

    Parameters
    ----------
    message : str
        One line; each argument it names between backticks as in a call (``"give `white=...` or
        `white_dir=...`"``, ``"`aperture=2.8` is ..."``), each how-to in Python too. ``str(error)`` is the
        message without the backticks (what a Python caller reads), ``error.marked`` as given (what a command
        words with its flags), ``error.arguments`` the names of the arguments it concerns (``["white",
        "white_dir"]``).
    """

    def __init__(self, message: str):
        self.marked = " ".join(str(message).split())
        self.arguments = arguments(self.marked)
        super().__init__(python_words(self.marked))

    def __reduce__(self):
        return type(self), (self.marked,)


class LfprocWarning(UserWarning):
    """Something the user should know that does not stop the work: an untrustworthy grid fit, slices whose
    border band is less refocused, a decode without devignetting.

    Library calls never print; they warn with this category (``warnings.warn(..., LfprocWarning)``), so a
    notebook can filter them (``warnings.simplefilter("ignore", lfproc.LfprocWarning)``). The commands
    print each as one line on stderr. Its message is marked as :class:`LfprocError`'s: ``str(warning)`` in
    Python words, ``warning.marked`` as given, ``warning.arguments`` the names of the arguments it concerns.
    """

    def __init__(self, message: str = ""):
        self.marked = str(message)
        self.arguments = arguments(self.marked)
        super().__init__(python_words(self.marked))

    def __reduce__(self):
        return type(self), (self.marked,)


def warn(message: str, category: type = LfprocWarning) -> None:
    """Warn ``message`` (an :class:`LfprocWarning` unless ``category`` says otherwise) at the caller's line: the
    first frame outside the lfproc package, however deep inside lfproc the warning is raised.

    Parameters
    ----------
    message : str
        One line naming the input and what to do, its arguments marked (``"`white=`"``; never flags).
    category : type, optional
        A ``Warning`` subclass (default :class:`LfprocWarning`).

    Returns
    -------
    None
    """
    frame, level = sys._getframe(1), 2   # stacklevel 2: the frame that called warn()
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE + os.sep):
        frame, level = frame.f_back, level + 1
    text = category(message) if issubclass(category, LfprocWarning) else python_words(message)
    warnings.warn(text, category, stacklevel=level)
