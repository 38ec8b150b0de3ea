"""Choosing and checking Lytro white images: same camera serial, nearest zoom and focus steps.

A camera's calibration folder holds white images (flat-field exposures, ``"modulationFrame": true``)
for many zoom and focus motor positions. The one for a capture has the capture's serial and the
nearest zoom step, then the nearest focus step. A white image of another camera, or of a zoom whose
main lens focal length differs by more than `ZOOM_TOLERANCE`, misplaces every micro image: refused.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import LfprocError
from ._lytro_metadata import LytroMetadata

#: the largest relative difference of main lens focal lengths (zoom) between capture and white image
ZOOM_TOLERANCE = 0.02
_FIX_DIR = "pass the calibration folder of the camera that took it (`white_dir=`) or a matching `white=`"


@dataclass(frozen=True)
class WhiteChoice:
    """The white image picked for a capture, its metadata and one line saying why."""

    path: str
    metadata: LytroMetadata
    reason: str


def check_white_matches(capture: LytroMetadata, white: LytroMetadata) -> None:
    """Refuse a white image of another camera (serial) or zoom (focal length beyond `ZOOM_TOLERANCE`).

    Raises
    ------
    LfprocError
        Naming the white image, the capture and what differs.
    """
    if capture.serial and white.serial and capture.serial != white.serial:
        raise LfprocError(f"{white.source}: white image of camera {white.serial}, but {capture.source} was taken "
                          f"by camera {capture.serial}; {_FIX_DIR}")
    if (capture.width, capture.height) != (white.width, white.height):
        raise LfprocError(f"{white.source}: white image of {white.width} x {white.height} pixels, but "
                          f"{capture.source} has {capture.width} x {capture.height}; {_FIX_DIR}")
    f_capture, f_white = capture.focal_length_m, white.focal_length_m
    if f_capture and f_white and abs(f_white - f_capture) > ZOOM_TOLERANCE * f_capture:
        raise LfprocError(f"{white.source}: white image taken at another zoom (focal length {f_white * 1e3:.2f} mm, "
                          f"zoom step {_step(white.zoom_step)}) than {capture.source} ({f_capture * 1e3:.2f} mm, "
                          f"zoom step {_step(capture.zoom_step)}); {_FIX_DIR}")


def pick_white_image(capture: LytroMetadata, folder: str | os.PathLike) -> WhiteChoice:
    """The white image in ``folder`` (searched recursively) for a capture: same serial, nearest zoom, focus.

    Candidates are Lytro raw pairs and containers whose metadata does not say
    ``"modulationFrame": false``. Among those of the capture's serial (all of them when the capture
    has no serial), the nearest zoom step wins, then the nearest focus step, then the name.

    Raises
    ------
    LfprocError
        No folder, no white image in it, none of this camera, or the nearest of another zoom.
    """
    from ._lytro_read import read_lytro_metadata

    folder = os.fspath(folder)
    if not os.path.isdir(folder):
        raise LfprocError(f"{folder}: `white_dir=` must be a folder of the camera's calibration files (white "
                          f"images with their metadata); check the path")
    candidates, serials = [], set()
    for path in _lytro_files(folder):
        try:
            meta = read_lytro_metadata(path)
        except LfprocError:
            continue    # not a readable white image: other calibration files live there too
        if meta.modulation_frame is False:
            continue
        serials.add(meta.serial or "unknown")
        if capture.serial is None or meta.serial is None or meta.serial == capture.serial:
            candidates.append(meta)
    if not candidates:
        found = f"white images of camera(s) {', '.join(sorted(serials))}" if serials else "no Lytro white images"
        raise LfprocError(f"{folder}: {found}, none of camera {capture.serial} that took {capture.source}; "
                          f"pass the calibration folder of that camera")
    best = min(candidates, key=lambda m: (_distance(m.zoom_step, capture.zoom_step),
                                          _distance(m.focus_step, capture.focus_step), m.source))
    check_white_matches(capture, best)
    reason = (f"white image {best.source} for {os.path.basename(capture.source)}: camera "
              f"{best.serial or 'serial unknown'}, zoom step {_step(best.zoom_step)} (capture "
              f"{_step(capture.zoom_step)}), focus step {_step(best.focus_step)} "
              f"(capture {_step(capture.focus_step)}); "
              f"nearest of {len(candidates)}")
    return WhiteChoice(path=best.source, metadata=best, reason=reason)


def _lytro_files(folder: str):
    from ._lytro_read import is_lytro_file

    for root, dirs, files in os.walk(folder):
        dirs.sort()
        for name in sorted(files):
            if os.path.splitext(name)[1].lower() in (".raw", ".lfp", ".lfr"):
                path = os.path.join(root, name)
                if is_lytro_file(path):
                    yield path


def _distance(a, b) -> float:
    return abs(a - b) if a is not None and b is not None else float("inf")


def _step(value) -> str:
    return "unknown" if value is None else f"{value:g}"
