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


def one_line(text: str) -> str:
    return " ".join(str(text or "").split())
