"""The lens grid from a white image: :func:`calibrate_white`, the one grid fitting of lfproc (``lfproc
calibrate``, ``white=`` of every decoding call, batch and the demo all fit here).

The result is a `LensGrid` that carries its `lfproc.grid.Calibration` (the white image and camera it was
fitted to, the fit's texture ratio, pitch uncertainty and implied exit pupil, the ``made_from`` record of
`lfproc.inputs`), so ``grid.save(path)`` writes exactly what ``lfproc calibrate -o`` writes.
"""

from __future__ import annotations

import dataclasses
import os

from ..errors import warn
from ..grid import Calibration, LensGrid


def calibrate_white(white, camera, dark=None, *, white_is_white: bool = False) -> LensGrid:
    """The micro-lens grid fitted to a white image, with what it was fitted from.

    Parameters
    ----------
    white : str, os.PathLike or ndarray
        The white image: a file (any image or raw the commands read, a Lytro raw) or its linear sensor
        values ``(H, W)`` (a Bayer mosaic of ``camera.cfa``) or ``(H, W, C)``.
    camera : Camera, str or os.PathLike
        The camera, or a file that describes it (:func:`lfproc.read_camera`: a camera TOML, napari-LF's
        ``metadata.txt``, a Lytro file).
    dark : str, os.PathLike or ndarray, optional
        A dark frame of the same size, subtracted from the white image (recorded in the grid: decoding with
        it subtracts the same one).
    white_is_white : bool
        Say that ``white`` is a white image: skip the check that refuses a capture of a scene given as one
        (docs/inputs.md).

    Returns
    -------
    LensGrid
        Its ``calibration`` (`lfproc.grid.Calibration`) says what it was fitted from; ``grid.save(path)``
        writes the grid file every ``grid=`` takes (exactly what ``lfproc calibrate`` writes).

    Raises
    ------
    LfprocError
        A file that cannot be read, a dark frame of another size, a capture of a scene given as the white
        image, or no lens lattice found (one line naming the file).

    Warns
    -----
    LfprocWarning
        An untrustworthy fit, or an exit pupil the camera file contradicts.
    """
    from ..inputs import check_same_sensor, subtract_dark
    from ._read import _camera, _capture, _probe

    camera = _camera(camera)
    white_facts = _probe(white, camera)   # headers first: a bad file fails before any pixel is read
    dark_facts = None if dark is None else _probe(dark, camera)
    if dark_facts is not None:
        check_same_sensor(dark_facts, white_facts, "dark frame", "white image")
    dark_capture = None if dark is None else _capture(dark, camera, "dark")
    white_capture = subtract_dark(_capture(white, camera, "white"), dark_capture, "white image")
    return fit_grid(white_capture, camera, dark_capture, white_is_white=white_is_white)


def fit_grid(white, camera, dark=None, *, white_is_white: bool = False) -> LensGrid:
    """The grid fitted to a white `lfproc.io.Capture` (dark frame subtracted already; ``dark``, the dark
    `Capture`, is recorded), with its `Calibration`; what the fit warns about is warned (`LfprocWarning`)."""
    from ..calibrate import exit_pupil_warning, find_grid, implied_exit_pupil
    from ..inputs import ImageFacts, check_white_is_white, made_from

    cfa = white.cfa if white.data.ndim == 2 else "none"
    estimate = find_grid(white.data, kind=camera.grid, approx_pitch_px=camera.pitch_px, cfa=cfa,
                         source=white.source)
    check_white_is_white(white.source, white.data, cfa, estimate.grid, white_is_white=white_is_white,
                         texture=estimate.texture)
    pupil = implied_exit_pupil(estimate.grid.pitch_px, estimate.pitch_sigma_px, camera)
    for line in filter(None, (*estimate.warnings, exit_pupil_warning(white.source, pupil, camera))):
        warn(line.replace(": warning: ", ": ", 1))
    white_file, dark_file = _file(white.source), None if dark is None else _file(dark.source)
    calibration = Calibration(
        white_image=white_file and os.path.abspath(white_file), camera=_camera_file(camera),
        texture_ratio=estimate.texture, micro_image_scale=pupil.scale, micro_image_scale_sigma=pupil.scale_sigma,
        implied_exit_pupil_distance_mm=pupil.distance_mm, implied_exit_pupil_range_mm=tuple(pupil.range_mm),
        pitch_sigma_px=estimate.pitch_sigma_px,
        made_from=made_from(camera, ImageFacts.of_capture(white), _hash(white_file),
                            None if dark is None else ImageFacts.of_capture(dark), _hash(dark_file)),
        measured_centers_xy_px=estimate.centers_xy_px, inlier=estimate.inlier)
    return dataclasses.replace(estimate.grid, calibration=calibration)


def _file(source) -> str | None:
    """The file a `Capture` was read from, or None for one made from an array."""
    return source if isinstance(source, str) and os.path.isfile(source) else None


def _hash(path) -> str | None:
    from ..inputs import file_hash

    return None if path is None else file_hash(path)


def _camera_file(camera) -> str | None:
    """The camera file ``camera`` was read from (absolute), or None (built in Python, from Lytro metadata)."""
    from ._setup import camera_file

    path = camera_file(camera)
    return None if path is None else os.path.abspath(path)
