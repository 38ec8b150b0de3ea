"""Reading TOML input files (camera files, scene files) with one-line errors that name the file."""

from __future__ import annotations

import os
import sys

from .errors import LfprocError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised only on Python 3.10
    import tomli as tomllib


def read_toml(path: str | os.PathLike, kind: str, usage: str) -> dict:
    """Parse the TOML file at ``path``.

    Parameters
    ----------
    kind : str
        What the file is, for messages ("camera file").
    usage : str
        What the user should pass instead, for messages ("an existing TOML file to --camera").
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise LfprocError(f"{path}: {kind} not found; pass {usage}") from None
    except IsADirectoryError:
        raise LfprocError(f"{path}: is a directory, not a {kind}; pass {usage}") from None
    except tomllib.TOMLDecodeError as exc:
        raise LfprocError(f"{path}: not valid TOML ({exc}); fix the syntax of the {kind}") from None
    except UnicodeDecodeError:
        raise LfprocError(f"{path}: not a {kind} (not text: an image or other binary file?); pass {usage}") from None
    except OSError as exc:
        raise LfprocError(f"{path}: cannot read {kind} ({exc}); check the path and permissions") from None


def parse_toml(text: str, source: str, kind: str) -> dict:
    """Parse TOML text (e.g. a camera file stored inside a light field file)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise LfprocError(f"{source}: not valid TOML ({exc}); fix the syntax of the {kind}") from None
