"""JSON sidecars (contract: ``OUTDIR/NAME.EXT`` -> ``OUTDIR/NAME.json``)."""

from __future__ import annotations

import os
from typing import Mapping

from ..atomic import write_json_atomic
from ..errors import LfprocError


def sidecar_path(image_path: str | os.PathLike) -> str:
    """The contract's sidecar of ``OUTDIR/NAME.EXT``: ``OUTDIR/NAME.json``."""
    stem, extension = os.path.splitext(os.fspath(image_path))
    if extension.lower() == ".json":
        raise LfprocError(f"{image_path}: an image named .json would be its own sidecar; use an image extension")
    return stem + ".json"


def write_sidecar(image_path: str | os.PathLike, metadata: Mapping) -> str:
    """Write ``metadata`` as strict JSON (infinity as ``null``) next to the image, atomically.

    Returns
    -------
    str
        The sidecar's path (`sidecar_path`).
    """
    target = sidecar_path(image_path)
    try:
        write_json_atomic(target, metadata)
    except OSError as exc:
        raise LfprocError(f"{target}: cannot write sidecar ({exc.strerror or exc}); check the folder") from None
    return target
