"""What a command takes from Lytro metadata when the user gave less: the camera (no ``--camera``) and the
white image of a calibration folder (``--white-dir``), each said in one line on stderr.

The library (`lfproc.read_light_field`) does the same without printing: a camera from metadata comes with
an `lfproc.LfprocWarning`, and ``white_dir=`` picks silently.
"""

from __future__ import annotations

import os
import sys

from ..camera import Camera
from ..errors import LfprocError


def white_image_for(captures, white: str | None = None, white_dir: str | None = None) -> str | None:
    """``--white`` as given, or the white image ``--white-dir`` picks for the first capture (said on stderr)."""
    from ..io import pick_white_image

    if white is not None and white_dir is not None:
        raise LfprocError("give --white WHITE or --white-dir DIR, not both")
    if white_dir is None:
        return white
    first = captures[0] if captures else None
    metadata = _lytro_metadata(first)
    if metadata is None:
        raise LfprocError(f"--white-dir {white_dir}: picks a white image by the metadata of Lytro captures, but "
                          f"{first or 'no capture'} is not a Lytro file; pass --white WHITE instead")
    choice = pick_white_image(metadata, white_dir)
    print(f"lfproc: {choice.reason}", file=sys.stderr)
    return choice.path


def camera_for_captures(camera_file: str | None, captures, focus_distance_mm: float | None = None) -> Camera:
    """The camera of ``--camera FILE``, or without one the camera in the first Lytro capture's metadata.

    The metadata has no focus distance: the main lens is taken as focused at infinity (or at
    ``focus_distance_mm``), and one line on stderr says so and how to fix it.
    """
    from ..io import lytro_camera

    if camera_file is not None:
        return Camera.from_toml(camera_file)
    first = _lytro_metadata(captures[0]) if captures else None
    if first is None:
        where = f"{captures[0]}: " if captures else ""
        raise LfprocError(f"{where}decoding a capture needs --camera CAM (a camera TOML file); only Lytro files "
                          f"carry their camera in their metadata")
    built = lytro_camera(first, focus_distance_mm)
    focus = "focused at infinity (the metadata has no focus distance)" if focus_distance_mm is None else \
        f"focused at {focus_distance_mm:g} mm"
    print(f"lfproc: camera from {first.source}'s metadata (Lytro {first.model}), main lens {focus}; for other "
          f"settings write it with 'lfproc camera {first.source} -o camera.toml' and pass --camera",
          file=sys.stderr)
    return built.camera


def _lytro_metadata(path):
    """The Lytro metadata of the file ``path``, or None (no path, or not a Lytro file)."""
    from ..io import is_lytro_file, read_lytro_metadata

    if path is None or not os.path.isfile(path) or not is_lytro_file(path):
        return None
    return read_lytro_metadata(path)
