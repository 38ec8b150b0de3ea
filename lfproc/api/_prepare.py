"""From a camera, a white image, a lens grid and a dark frame to a `DecodeSetup`: :func:`prepare_decoding`, the
one path every decoding takes (:func:`lfproc.read_light_field`, the commands, batch, the demo, the viewer).

``white`` (a white image) fits the grid (:func:`lfproc.calibrate_white`) and devignettes; ``grid`` (a
`LensGrid`, or the grid file its ``save`` wrote) is used as it is and devignettes with the white image it was
fitted to (if that file is still there, unchanged); both together use the given grid and the given white
image. Without any white image captures are decoded without devignetting (warned). ``dark`` is subtracted
from the white image and every capture; a grid fitted with one records it, and decoding with that grid
subtracts it again (docs/inputs.md). Each input may be a file or an array (a grid: a `LensGrid` or its file):
the same checks and steps either way.

Cheap checks come first: camera, grid, white image, dark frame and the captures' headers are checked against
each other (lattice kind, micro image pitch, sensor size, Bayer pattern) before any of them is read in full.
Lytro captures: ``white_dir`` picks the white image of the first capture's camera with the nearest zoom and
focus steps (said in ``DecodeSetup.white_note``); a Lytro white image of another camera or zoom is refused.
Messages name the Python arguments (``white=``, ``grid=``, ``dark=``, ``white_dir=``).
"""

from __future__ import annotations

import dataclasses
import os

from ..errors import LfprocError, warn
from ..grid import LensGrid
from ._setup import DecodeSetup, camera_file

_PATH = (str, os.PathLike)
#: where a grid comes from, for a Python caller (the commands word it as their command)
GRID_FROM_API = "(`a LensGrid from lfproc.calibrate_white, or its saved file`)"


def prepare_decoding(camera=None, white=None, grid=None, dark=None, *, white_dir=None, captures=(),
                     decode_interpolation: str = "linear", demosaic: str = "fast", cache: bool = False,
                     white_is_white: bool = False) -> DecodeSetup:
    """Check the inputs against each other, fit the grid where none is given and derive the decoder: once for
    any number of captures of one camera (``setup.decode(capture)`` for each).

    Parameters
    ----------
    camera : Camera, str or os.PathLike, optional
        The camera or its TOML file; for Lytro ``captures`` without one, the camera in the first one's
        metadata (main lens focused at infinity, warned).
    white : str, os.PathLike or ndarray, optional
        The white image: corrects vignetting, and the grid is fitted to it when ``grid`` is None.
    grid : LensGrid, str or os.PathLike, optional
        The lens grid (:func:`lfproc.calibrate_white`), or the grid file it was saved to. One of ``white``,
        ``grid`` or ``white_dir`` is needed.
    dark : str, os.PathLike or ndarray, optional
        A dark frame, subtracted from the white image and every capture.
    white_dir : str or os.PathLike, optional
        A Lytro calibration folder: the white image of the first capture's camera with the nearest zoom and
        focus steps.
    captures : sequence of str or os.PathLike
        The capture files that will be decoded: their headers are checked now, before the white image is
        read; ``white_dir`` picks for the first.
    decode_interpolation, demosaic, white_is_white
        As :func:`lfproc.read_light_field`'s.
    cache : bool
        Keep the decoder derived from the white image in the decoder cache on disk and reuse it from there
        (docs/cache.md; the commands do). Default False: nothing is written.

    Returns
    -------
    DecodeSetup
        Picklable; ``setup.decode(capture)`` decodes one capture (a file or an array).

    Raises
    ------
    LfprocError
        Missing or mismatched inputs (one line naming the argument and the fix).
    """
    from ..inputs import (ImageFacts, check_grid_fits_camera, check_same_sensor, measured_m_hat, reference_facts,
                          subtract_dark)
    from ..io import read_capture
    from ..provenance import file_inputs
    from ._calibrate import fit_grid
    from ._read import _camera, _capture, _probe

    captures = [os.fspath(path) for path in captures]
    camera = _camera(camera, captures[0] if captures else None)
    if white is not None and white_dir is not None:
        raise LfprocError("give `white=...` or `white_dir=...`, not both")
    if white is None and grid is None and white_dir is None:
        raise LfprocError(f"decoding a capture needs `white=...` (a white image), `grid=...` {GRID_FROM_API} or "
                          f"`white_dir=...` (a Lytro calibration folder)")
    first = lytro_metadata_of(captures[0]) if captures else None
    white_note = None
    if white_dir is not None:
        white, white_note = white_from_folder(os.fspath(white_dir), first, captures[0] if captures else None)
    if grid is not None:
        grid = _grid(grid)
        check_grid_fits_camera(camera, grid)
    white_path = os.fspath(white) if isinstance(white, _PATH) else _recorded_white(grid) if white is None else None
    white_capture = None if white is None or white_path is not None else _capture(white, camera, "white")
    white_facts = _probe(white_path, camera) if white_path else \
        ImageFacts.of_capture(white_capture) if white_capture is not None else None
    recorded = reference_facts(grid)
    if white_facts is not None and recorded is not None:
        check_same_sensor(white_facts, recorded, "white image", f"white image that {_name(grid)} was calibrated on")
    reference = white_facts or recorded
    dark_path = _dark_for(dark, grid)
    dark_capture = None if dark is None or dark_path is not None else _capture(dark, camera, "dark")
    if dark_path is not None or dark_capture is not None:
        dark_facts = _probe(dark_path, camera) if dark_path else ImageFacts.of_capture(dark_capture)
        check_same_sensor(dark_facts, reference, "dark frame", _reference_what(reference, white_facts, grid))
    _check_capture_headers(captures, camera, reference, grid, _reference_what(reference, white_facts, grid))
    white_metadata = lytro_metadata_of(white_path)
    if white_metadata is not None and white_metadata.modulation_frame is False:
        warn(f"{white_path}: its metadata marks it as a capture, not a white image (modulationFrame "
             f"false); pass a white image from the camera's calibration folder")
    if first is not None and white_metadata is not None:
        from ..io import check_white_matches
        check_white_matches(first, white_metadata)
    # the expensive part: the dark frame, the white image (to fit the grid, or as an array), the decoder
    if dark_path is not None:
        dark_capture = read_capture(dark_path, camera)
    if grid is None:
        white_capture = subtract_dark(read_capture(white_path, camera) if white_capture is None else white_capture,
                                      dark_capture, "white image")
        grid = fit_grid(white_capture, camera, dark_capture, white_is_white=white_is_white)
    elif white_capture is not None:
        white_capture = subtract_dark(white_capture, dark_capture, "white image")
    elif white_path is None:
        recorded_white = grid.calibration.white_image if grid.calibration is not None else None
        warn(f"{_name(grid)}: no white image available (recorded: {recorded_white}); decoding without "
             f"devignetting; pass `white=...` to correct vignetting")
    measured = measured_m_hat(camera, grid.pitch_px, grid.source or "the calibration")
    setup = DecodeSetup(measured.camera, grid, white=white_capture, white_path=white_path, dark=dark_capture,
                        reference=reference, inputs=file_inputs(camera=camera_file(camera), grid=grid.source,
                                                                white=white_path, dark=dark_path),
                        decode_interpolation=decode_interpolation, demosaic=demosaic, cache=cache,
                        white_is_white=white_is_white, white_metadata=white_metadata, white_note=white_note,
                        m_hat_note=measured.note)
    setup.prepare()
    # the decoder holds what decoding needs of the white image: its pixels need not stay in memory (nor travel
    # to batch workers); the file is read again only if the decoder must be derived again
    return dataclasses.replace(setup, white=None) if white_path is not None else setup


def _grid(grid) -> LensGrid:
    if isinstance(grid, _PATH):
        return LensGrid.load(grid)
    if not isinstance(grid, LensGrid):
        raise LfprocError(f"`grid=` must be a LensGrid (from lfproc.calibrate_white) or the path of its saved file, "
                          f"got {type(grid).__name__}")
    return grid


def _name(grid) -> str:
    return grid.source or "the grid"


def _reference_what(reference, white_facts, grid) -> str:
    """How messages name the image every other must match."""
    if reference is None or reference is white_facts:
        return "white image"
    return f"white image that {_name(grid)} was calibrated on"


def _recorded_white(grid) -> str | None:
    """The white image a grid was fitted to, if that file is still there with the content it had then."""
    from ..inputs import same_file_content

    path = grid.calibration.white_image if grid is not None and grid.calibration is not None else None
    if not path or not os.path.exists(path):
        return None
    if not same_file_content(path, (grid.calibration.white_facts or {}).get("hash")):
        raise LfprocError(f"{path}: this white image, recorded in {_name(grid)}, has changed since the grid was "
                          f"fitted to it (its content hash differs); fit the grid again, or pass `white=...` to "
                          f"devignette with it anyway")
    return path


def _dark_for(dark, grid) -> str | None:
    """The dark frame's file: ``dark`` as given (refused if the grid recorded another), or the one the grid
    recorded; None for none, or for a dark frame given as an array."""
    from ..inputs import file_hash, same_file_content

    recorded = grid.calibration.dark_facts if grid is not None and grid.calibration is not None else None
    if dark is not None:
        if not isinstance(dark, _PATH):
            return None
        dark = os.fspath(dark)
        if recorded and recorded.get("hash") and os.path.isfile(dark) and file_hash(dark) != recorded["hash"]:
            raise LfprocError(f"{dark}: this dark frame differs from the one {_name(grid)} was fitted with "
                              f"({recorded.get('path')}); pass that one, or fit the grid again with `dark={dark}`")
        return dark
    if not recorded:
        return None
    path = recorded.get("path")
    if not path:
        raise LfprocError(f"{_name(grid)}: was fitted with a dark frame given as an array; pass it again as `dark=`")
    if not same_file_content(path, recorded.get("hash")):
        raise LfprocError(f"{_name(grid)}: was fitted with the dark frame {path}, which is missing or has changed "
                          f"since; pass the same dark frame with `dark=...`, or fit the grid again")
    return path


def _check_capture_headers(captures, camera, reference, grid, reference_what: str) -> None:
    """Every capture's header read and checked before the white image is read; when none of them could be
    decoded, the first one's problem is the error (else each fails in its turn)."""
    from ..inputs import check_fits_grid_extent, check_same_sensor, probe_image
    from ..lightfield import is_lightfield_file

    errors = []
    paths = [path for path in captures if not is_lightfield_file(path)]
    for path in paths:
        try:
            facts = probe_image(path, camera)
            if reference is not None:
                check_same_sensor(facts, reference, "capture", reference_what)
            elif grid is not None:
                check_fits_grid_extent(facts, grid)
        except LfprocError as exc:
            errors.append(exc)
    if paths and len(errors) == len(paths):
        raise errors[0]


def lytro_metadata_of(path):
    """The Lytro metadata of the file ``path``, or None (no path, or not a Lytro file)."""
    from ..io import is_lytro_file, read_lytro_metadata

    if path is None or not os.path.isfile(path) or not is_lytro_file(path):
        return None
    return read_lytro_metadata(path)


def white_from_folder(folder: str, capture_metadata, capture_path) -> tuple[str, str]:
    """(path, reason): the white image of a Lytro calibration folder for a capture of that metadata (same
    camera, nearest zoom and focus steps), and one line saying which and why."""
    from ..io import pick_white_image

    if capture_metadata is None:
        raise LfprocError(f"`white_dir={folder}`: picks a white image by the metadata of Lytro captures, but "
                          f"{capture_path or 'no capture'} is not a Lytro file; pass `white=...` instead")
    choice = pick_white_image(capture_metadata, folder)
    return choice.path, choice.reason
