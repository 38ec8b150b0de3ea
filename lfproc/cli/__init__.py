"""The ``lfproc`` command: one module per subcommand, each with ``register(subparsers)``.

Subcommand modules import numba, OpenCV and OpenImageIO only inside their ``run`` function, so
``lfproc geometry`` starts in a fraction of a second. An `LfprocError` becomes one line on stderr and
exit status 2, the arguments and how-tos its message marks in the command's words (:mod:`.words`); anything
else is a bug and exits with status 1 and a traceback.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import warnings
from importlib import import_module

from ..errors import LfprocError
from .words import command_words

#: subcommand modules in the order ``lfproc --help`` lists them
COMMANDS = ("geometry", "info", "camera", "simulate", "calibrate", "decode", "refocus", "views", "depth", "deconvolve",
            "viewer", "batch", "export", "demo")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors (exit status 2, like every bad input)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="lfproc", description="Standard Plenoptic Camera light fields: refocusing, viewpoints "
                                                "and the metric geometry of every output.")
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in COMMANDS:
        import_module(f"{__name__}.{name}").register(sub)
    return parser


def _version() -> str:
    from .. import __version__
    return f"lfproc {__version__}"


def main(argv=None) -> int:
    from .common import join_negative_values

    parser = build_parser()
    args = parser.parse_args(join_negative_values(list(sys.argv[1:] if argv is None else argv)))
    try:
        with _plain_warnings(args.command):
            status = args.func(args)
    except LfprocError as exc:
        print(f"lfproc {args.command}: error: {command_words(exc.marked, args.command)}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # `lfproc geometry | head`: the reader left, which is not an error
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print(f"lfproc {args.command}: interrupted; finished outputs are complete, nothing partial was written",
              file=sys.stderr)
        return 130
    return int(status or 0)


@contextlib.contextmanager
def _plain_warnings(command: str):
    """Warnings reach the user as one plain line on stderr, like errors (no Python source line), in the
    commands' words, each once per command (a check that runs before decoding and again on the decoded light
    field, or once per capture, says it once)."""
    said = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = f"lfproc {command}: warning: {command_words(getattr(message, 'marked', str(message)), command)}"
        if text not in said:
            said.add(text)
            print(text, file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.showwarning = show
        yield


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
