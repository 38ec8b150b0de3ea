"""Jobs: one capture and what to make of it, as plain picklable data; input expansion."""

from __future__ import annotations

import glob
import hashlib
import json
import os
from dataclasses import dataclass, fields

from ..api import DEFAULT_INTERPOLATION
from ..errors import LfprocError

#: image extensions a folder input is searched for (case-insensitive)
CAPTURE_EXTENSIONS = (".dng", ".cr2", ".cr3", ".nef", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw",
                      ".tif", ".tiff", ".png", ".exr", ".lfr", ".lfp", ".raw", ".npz")
#: Job fields that are not parameters of the outputs (where they go, and the camera file's text,
#: which the fingerprint hashes separately)
_NOT_PARAMETERS = ("source", "stem", "outdir", "camera_toml", "dark", "camera_path", "white_is_white")


@dataclass(frozen=True)
class Job:
    """One capture to process; every field is plain data so it pickles cheaply to any worker.

    Paths are absolute: a worker on another machine resolves them on the shared file system.
    """

    source: str                 # the capture, or a light field from lfproc decode (.lfp.npz)
    stem: str                   # output name prefix
    outdir: str                 # output folder
    camera_toml: str            # the camera file's text ("" when every input is a decoded light field)
    calib: str | None           # GRID.json (from lfproc calibrate) or None
    white: str | None           # white image or None
    refocus_a: tuple            # refocus parameters a (empty: no refocusing)
    views: bool                 # write the viewpoint images
    fmt: str = "tiff"
    interpolation: str = DEFAULT_INTERPOLATION
    decode_interpolation: str = "linear"
    demosaic: str = "fast"
    upsample: int = 1           # refocused slices on an upsample-times finer grid
    mosaic: bool = False        # with views: also the mosaic of all views
    gif: bool = False           # with views: also the animation
    inside_aperture: bool = False  # with views: only those inside the main lens aperture
    aperture: float | None = None  # synthetic aperture f-number for the slices (None: every view with light)
    dark: str | None = None     # dark frame (--dark) or None; stamped into the fingerprint when given
    stack: str | None = None    # with slices: also one z-stack file, "imagej" or "ome" (lfproc refocus --stack)
    camera_path: str | None = None  # the camera file (--camera), recorded in the outputs' provenance
    white_is_white: bool = False  # --white-is-white: the white image is not checked for a scene
    deconvolve: dict | None = None  # lfproc.deconvolve's keyword arguments (z_um, iterations, superres, ...) or None

    def parameters(self) -> dict:
        """The parameters that shape this capture's outputs, as recorded in the manifest."""
        return {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else v)
                for f in fields(self) if f.name not in _NOT_PARAMETERS
                and not (f.name == "deconvolve" and self.deconvolve is None)}   # earlier manifests stay valid

    def fingerprint(self) -> str:
        """Changes whenever the capture, the camera, the white image, the grid file, the dark frame, lfproc's version or
        any parameter that shapes the outputs changes (not when OUTDIR moves)."""
        from .. import __version__

        inputs = [file_stamp(p) for p in (self.source, self.calib, self.white)]
        if self.dark is not None:   # only then: manifests written without a dark frame stay valid
            inputs.append(file_stamp(self.dark))
        payload = json.dumps([__version__, self.source, self.stem, self.camera_toml, self.parameters(), inputs],
                             sort_keys=True, default=str)
        return hashlib.sha256(payload.encode()).hexdigest()[:32]


@dataclass(frozen=True)
class JobResult:
    """What became of one capture: ``outputs`` are image paths (each with its sidecar ``NAME.json``);
    ``warnings`` the :class:`lfproc.LfprocWarning` messages its processing gave (each distinct one once);
    ``error`` and ``warnings`` with their arguments marked (``error.marked``, :mod:`lfproc.errors`)."""

    source: str
    status: str                 # "done" | "failed" | "skipped" | "cancelled" (stopped by an interrupt: nothing written)
    outputs: tuple = ()
    error: str | None = None
    seconds: float = 0.0
    warnings: tuple = ()


def file_stamp(path: str | None) -> list | None:
    """``[path, size, mtime_ns]`` of a file (size and time None if it is missing), or None for no path."""
    if path is None:
        return None
    try:
        st = os.stat(path)
        return [path, st.st_size, st.st_mtime_ns]
    except OSError:
        return [path, None, None]


def expand_inputs(inputs: list[str]) -> list[str]:
    """Files, folders (their capture files, sorted by name) and glob patterns (sorted matches) → absolute
    paths in the order given, without duplicates."""
    found = []
    for item in inputs:
        if os.path.isdir(item):
            names = sorted(os.listdir(item))
            found += [os.path.join(item, n) for n in names
                      if n.lower().endswith(CAPTURE_EXTENSIONS) and os.path.isfile(os.path.join(item, n))]
        elif any(ch in item for ch in "*?["):
            matches = sorted(glob.glob(item))
            if not matches:
                raise LfprocError(f"{item}: the pattern matches no file; check the pattern")
            found += [m for m in matches if os.path.isfile(m)]
        elif os.path.isfile(item):
            found.append(item)
        else:
            raise LfprocError(f"{item}: no such file or folder; give capture files, folders or glob patterns")
    unique = list(dict.fromkeys(os.path.abspath(p) for p in found))
    if not unique:
        raise LfprocError(f"no captures found in {' '.join(inputs)}; folders are searched for "
                          f"{', '.join(CAPTURE_EXTENSIONS)}")
    return unique


