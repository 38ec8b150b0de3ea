"""From files or arrays to a `LightField`: :func:`read_light_field` and :func:`calibrate_white`.

The same steps as the commands (:mod:`lfproc.pipeline`: the cheap checks of :mod:`lfproc.inputs` first,
then calibration and decoding), without their side effects: nothing printed, and the decoder cache
(:mod:`lfproc.decoder_cache`, on disk) used only with ``cache=True``.
"""

from __future__ import annotations

import os
import warnings

import numpy as np

from ..camera import Camera
from ..errors import LfprocError, LfprocWarning
from ..grid import LensGrid
from ..lightfield import LightField, is_lightfield_file

_PATH = (str, os.PathLike)


def calibrate_white(white, camera, dark=None, *, white_is_white: bool = False) -> LensGrid:
    """The micro-lens grid fitted to a white image (what ``lfproc calibrate`` writes to GRID.json).

    Parameters
    ----------
    white : str, os.PathLike or ndarray
        The white image: a file (any image or raw the commands read, a Lytro raw) or its linear sensor
        values ``(H, W)`` (a Bayer mosaic of ``camera.cfa``) or ``(H, W, C)``.
    camera : Camera, str or os.PathLike
        The camera, or a file that describes it (:func:`lfproc.read_camera`: a camera TOML, napari-LF's
        ``metadata.txt``, a Lytro file).
    dark : str, os.PathLike or ndarray, optional
        A dark frame of the same size, subtracted from the white image.
    white_is_white : bool
        Say that ``white`` is a white image: skip the check that refuses a capture of a scene given as one
        (the commands' ``--white-is-white``; docs/inputs.md).

    Returns
    -------
    LensGrid

    Warns
    -----
    LfprocWarning
        An untrustworthy fit, or an exit pupil the camera file contradicts.
    """
    from ..inputs import subtract_dark
    from ..pipeline import calibrate_white as fit

    camera = _camera(camera)
    dark_capture = None if dark is None else _capture(dark, camera, "dark")
    white_capture = subtract_dark(_capture(white, camera, "white"), dark_capture, "white image")
    return fit(white_capture, camera, white_is_white=white_is_white)


def read_light_field(capture, camera=None, white=None, grid=None, dark=None, *, white_dir=None,
                     decode_interpolation: str = "linear", demosaic: str = "fast", cache: bool = False,
                     white_is_white: bool = False) -> LightField:
    """Decode a capture into a light field (or read one that ``lfproc decode`` saved).

    Parameters
    ----------
    capture : str, os.PathLike or ndarray
        Any capture the commands read (camera raw, TIFF/PNG/EXR, a Lytro ``.lfp``/``.lfr`` or raw), a saved
        light field (``.lfp.npz``, which carries its camera and grid: the other arguments are not needed),
        or the linear sensor values ``(H, W)`` (a Bayer mosaic of ``camera.cfa``) or ``(H, W, C)``.
    camera : Camera, str or os.PathLike, optional
        The camera, or a file that describes it (:func:`lfproc.read_camera`: a camera TOML, napari-LF's
        ``metadata.txt``, a Lytro file); for a Lytro capture without one, the camera in its metadata (main lens
        focused at infinity, with a :class:`LfprocWarning`).
    white : str, os.PathLike or ndarray, optional
        The white image: corrects vignetting, and the grid is fitted to it when ``grid`` is None.
    grid : LensGrid, str or os.PathLike, optional
        The lens grid (:func:`calibrate_white`), or a GRID.json written by ``lfproc calibrate`` (whose
        recorded white image then devignettes, if it still exists). One of ``white``, ``grid`` or
        ``white_dir`` is needed; a grid without any white image decodes without devignetting (warned).
    dark : str, os.PathLike or ndarray, optional
        A dark frame, subtracted from the white image and the capture.
    white_dir : str or os.PathLike, optional
        A Lytro calibration folder: the white image of the capture's camera with the nearest zoom and focus.
    decode_interpolation : {"nearest", "linear", "cubic", "lanczos"}
        Resampling of the sensor into micro images (the commands' ``--decode-interpolation``).
    demosaic : {"fast", "careful"}
        Bayer demosaicing (the commands' ``--demosaic``).
    cache : bool
        Keep the decoder derived from the white image in the decoder cache on disk and reuse it from there
        (docs/cache.md; the commands do). Default False: nothing is written.
    white_is_white : bool
        Say that ``white`` is a white image: skip the check that refuses a capture of a scene given as one
        (the commands' ``--white-is-white``).

    Returns
    -------
    LightField
        Without ``[decode] micro_image_px`` in the camera, m̂ is the largest odd integer not above the
        grid's measured micro image pitch (as the commands decode; ``lfproc.inputs.measured_m_hat``).
        With its camera, grid, view mask and ``inputs`` (the files it was made from, for provenance).

    Raises
    ------
    LfprocError
        Missing or mismatched inputs (one line naming the argument and the fix).
    """
    if isinstance(capture, _PATH) and is_lightfield_file(capture):
        return _saved(capture, camera)
    if isinstance(capture, _PATH) and not os.path.isfile(capture):
        raise LfprocError(f"{capture}: no such file; check the path")
    camera = _camera(camera, capture)
    if white_dir is not None:
        white = _white_in_folder(white, white_dir, capture)
    if isinstance(capture, _PATH) and _all_files(white, dark) and (grid is None or isinstance(grid, _PATH)
                                                                   or white is not None):
        from ..pipeline import load_lightfield, prepare_decoding

        _check_white_given(white, grid, None)
        with _warnings_said_once():
            setup = prepare_decoding(camera, _path(grid), _path(white), interpolation=decode_interpolation,
                                     demosaic_method=demosaic, grid=grid if isinstance(grid, LensGrid) else None,
                                     captures=[os.fspath(capture)],
                                     dark=_path(dark), cache=cache, white_is_white=white_is_white)
        return load_lightfield(os.fspath(capture), setup)
    return _from_arrays(capture, camera, white, grid, dark, decode_interpolation, demosaic, cache, white_is_white)


def _white_in_folder(white, folder, capture) -> str:
    """The white image of a Lytro calibration folder that matches ``capture`` (same camera, nearest zoom and
    focus steps; the commands' ``--white-dir``)."""
    from ..io import is_lytro_file, pick_white_image, read_lytro_metadata

    if white is not None:
        raise LfprocError("give white= or white_dir=, not both")
    if not isinstance(capture, _PATH) or not is_lytro_file(os.fspath(capture)):
        raise LfprocError("white_dir= picks a white image by the metadata of a Lytro capture, but capture= is not a "
                          "Lytro file; pass white= instead")
    return pick_white_image(read_lytro_metadata(os.fspath(capture)), os.fspath(folder)).path


def _check_white_given(white, grid, white_dir) -> None:
    if white is None and grid is None and white_dir is None:
        raise LfprocError("decoding a capture needs white= (a white image), grid= (a LensGrid from "
                          "lfproc.calibrate_white, or a GRID.json) or white_dir= (a Lytro calibration folder)")


def _saved(path, camera) -> LightField:
    """A light field saved by ``lfproc decode`` (or ``LightField.save``); ``camera`` only where it has none."""
    import dataclasses

    lf = LightField.load(path)
    if lf.camera is None:
        if camera is None:
            raise LfprocError(f"{path}: this light field carries no camera; pass camera=")
        camera = _camera(camera)
        if camera.m_hat != lf.m_hat:
            raise LfprocError(f"{path}: has {lf.m_hat}x{lf.m_hat} views but camera= has micro_image_px "
                              f"{camera.m_hat}; pass the camera it was decoded with")
        inputs = dict(lf.inputs or {})
        if isinstance(camera.source, str) and camera.source.lower().endswith(".toml"):
            inputs["camera"] = camera.source
        lf = dataclasses.replace(lf, camera=camera, inputs=inputs)
    return lf


def _from_arrays(capture, camera, white, grid, dark, decode_interpolation, demosaic, cache,
                 white_is_white=False) -> LightField:
    """The steps of :func:`lfproc.pipeline.prepare_decoding` for inputs given (partly) as arrays or objects."""
    from ..inputs import measured_m_hat, read_grid_record, subtract_dark
    from ..pipeline import DecodeSetup, camera_file, decode_capture, load_lightfield
    from ..pipeline import calibrate_white as fit
    from ..provenance import file_inputs

    _check_white_given(white, grid, None)
    dark_capture = None if dark is None else _capture(dark, camera, "dark")
    white_capture = None if white is None else subtract_dark(_capture(white, camera, "white"), dark_capture,
                                                             "white image")
    if isinstance(grid, _PATH):
        lattice = read_grid_record(os.fspath(grid)).grid
    elif grid is not None:
        if not isinstance(grid, LensGrid):
            raise LfprocError(f"grid= must be a LensGrid (from lfproc.calibrate_white) or a GRID.json path, got "
                              f"{type(grid).__name__}")
        lattice = grid
    else:
        lattice = fit(white_capture, camera, white_is_white=white_is_white)
    camera = measured_m_hat(camera, lattice.pitch_px, "grid").camera
    if white_capture is None:
        warnings.warn("no white image given: decoding without devignetting; pass white= to correct vignetting",
                      LfprocWarning, stacklevel=3)
    inputs = file_inputs(camera=camera_file(camera), grid=grid, white=white, dark=dark)
    setup = DecodeSetup(camera, lattice, white_capture, decode_interpolation, demosaic, dark=dark_capture,
                        cache=cache, inputs=inputs, white_is_white=white_is_white)
    if isinstance(capture, _PATH):
        return load_lightfield(os.fspath(capture), setup)
    return decode_capture(_capture(capture, camera, "capture"), setup)


def _capture(value, camera, what: str):
    """A path read as the commands read it, or an array taken as linear sensor values."""
    if isinstance(value, _PATH):
        from ..io import read_capture

        if not os.path.isfile(value):
            raise LfprocError(f"{value}: no such file (given as {what}=); check the path")
        return read_capture(os.fspath(value), camera)
    from ..io import Capture

    data = np.asarray(value)
    if data.ndim not in (2, 3) or data.dtype.kind not in "fiub" or min(data.shape) < 1:
        raise LfprocError(f"{what}= must be a path or an array of sensor values shaped (H, W) or (H, W, C), "
                          f"got {getattr(value, 'shape', type(value).__name__)}")
    cfa = (camera.cfa or "none") if data.ndim == 2 else "none"
    if data.ndim == 3 and data.shape[2] == 1:
        data, cfa = data[:, :, 0], "none"
    return Capture(np.ascontiguousarray(data, dtype=np.float32), cfa, f"{what} array")


def _camera(camera, capture=None) -> Camera:
    """``camera`` as a Camera (read from its file by `lfproc.read_camera`); without one, a Lytro capture's own
    (warned)."""
    if isinstance(camera, Camera):
        return camera
    if isinstance(camera, _PATH):
        from ..io import read_camera

        return read_camera(camera)
    if camera is not None:
        raise LfprocError(f"camera= must be a Camera or the path of a camera file (TOML, napari-LF's metadata.txt "
                          f"or a Lytro file), got {type(camera).__name__}")
    if isinstance(capture, _PATH):
        from ..io import is_lytro_file, lytro_camera, read_lytro_metadata

        if is_lytro_file(os.fspath(capture)):
            built = lytro_camera(read_lytro_metadata(os.fspath(capture)))
            warnings.warn(f"{capture}: camera from its metadata, main lens focused at infinity (the metadata has no "
                          f"focus distance); for other settings pass camera=", LfprocWarning, stacklevel=4)
            return built.camera
    raise LfprocError("decoding a capture needs camera= (a Camera or a camera TOML file); only Lytro files carry "
                      "their camera in their metadata")


def _path(value):
    return os.fspath(value) if isinstance(value, _PATH) else None


def _all_files(*values) -> bool:
    return all(v is None or isinstance(v, _PATH) for v in values)


class _warnings_said_once:
    """Warnings inside, as :class:`LfprocWarning` (a library's own category) whatever they were raised as."""

    def __enter__(self):
        self._catcher = warnings.catch_warnings(record=True)
        self._caught = self._catcher.__enter__()
        warnings.simplefilter("always")
        return self

    def __exit__(self, *exc):
        self._catcher.__exit__(*exc)
        for w in self._caught:
            category = w.category if issubclass(w.category, LfprocWarning) else LfprocWarning
            warnings.warn(str(w.message), category, stacklevel=3)
        return False
