"""From a file or an array to a `LightField`: :func:`read_light_field`, and how every call of the API takes its
inputs (a camera or its file; a capture, white image or dark frame as a file or an array).

Decoding goes the one way every command goes (:func:`lfproc.prepare_decoding`, then `DecodeSetup.decode`);
nothing is printed, and the decoder cache (:mod:`lfproc.decoder_cache`, on disk) is used only with ``cache=True``.
"""

from __future__ import annotations

import os
import warnings

import numpy as np

from ..camera import Camera
from ..errors import LfprocError, LfprocWarning, warn
from ..lightfield import LightField, is_lightfield_file

_PATH = (str, os.PathLike)


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
        The lens grid (:func:`lfproc.calibrate_white`), or the grid file its ``save`` wrote (what ``lfproc
        calibrate`` writes). The white image it was fitted to then devignettes, if that file is still there.
        One of ``white``, ``grid`` or ``white_dir`` is needed; a grid without any white image decodes without
        devignetting (warned).
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

    To decode many captures with one white image, make the setup once (:func:`lfproc.prepare_decoding`) and
    call its ``decode`` for each: this function does both for one capture.

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
        from ._setup import _missing_capture
        raise LfprocError(_missing_capture(os.fspath(capture)))
    from ._prepare import prepare_decoding

    with _warnings_said_once():
        setup = prepare_decoding(camera, white, grid, dark, white_dir=white_dir,
                                 captures=[capture] if isinstance(capture, _PATH) else [],
                                 decode_interpolation=decode_interpolation, demosaic=demosaic, cache=cache,
                                 white_is_white=white_is_white)
    return setup.decode(capture)


def _saved(path, camera) -> LightField:
    """A light field saved by ``lfproc decode`` (or ``LightField.save``); ``camera`` only where it has none."""
    import dataclasses

    lf = LightField.load(path)
    if lf.camera is None:
        if camera is None:
            raise LfprocError(f"{path}: this light field carries no camera; pass `camera=`")
        camera = _camera(camera)
        if camera.m_hat != lf.m_hat:
            raise LfprocError(f"{path}: has {lf.m_hat}x{lf.m_hat} views but `camera=` has micro_image_px "
                              f"{camera.m_hat}; pass the camera it was decoded with")
        inputs = dict(lf.inputs or {})
        if isinstance(camera.source, str) and camera.source.lower().endswith(".toml"):
            inputs["camera"] = camera.source
        lf = dataclasses.replace(lf, camera=camera, inputs=inputs)
    return lf


def _capture(value, camera, what: str):
    """A path read as the commands read it, a `Capture` as it is, or an array taken as linear sensor values."""
    from ..io import Capture

    if isinstance(value, _PATH):
        from ..io import read_capture

        return read_capture(os.fspath(value), camera)
    if isinstance(value, Capture):
        return value
    data = np.asarray(value)
    if data.ndim not in (2, 3) or data.dtype.kind not in "fiub" or min(data.shape) < 1:
        raise LfprocError(f"{what}= must be a path or an array of sensor values shaped (H, W) or (H, W, C), "
                          f"got {getattr(value, 'shape', type(value).__name__)}")
    cfa = (camera.cfa or "none") if data.ndim == 2 else "none"
    if data.ndim == 3 and data.shape[2] == 1:
        data, cfa = data[:, :, 0], "none"
    return Capture(np.ascontiguousarray(data, dtype=np.float32), cfa, f"{what} array")


def _probe(value, camera):
    """The header facts (`lfproc.inputs.ImageFacts`) of a file (a missing file or a folder refused in one line);
    None for an array."""
    from ..inputs import probe_image

    return probe_image(os.fspath(value), camera) if isinstance(value, _PATH) else None


def _camera(camera, capture=None) -> Camera:
    """``camera`` as a Camera (read from its file by `lfproc.read_camera`); without one, a Lytro capture's own
    (warned)."""
    if isinstance(camera, Camera):
        return camera
    if isinstance(camera, _PATH):
        from ..io import read_camera

        return read_camera(camera)
    if camera is not None:
        raise LfprocError(f"`camera=` must be a Camera or the path of a camera file (TOML, napari-LF's metadata.txt "
                          f"or a Lytro file), got {type(camera).__name__}")
    if isinstance(capture, _PATH):
        from ..io import is_lytro_file, lytro_camera, read_lytro_metadata

        if is_lytro_file(os.fspath(capture)):
            built = lytro_camera(read_lytro_metadata(os.fspath(capture)))
            warn(f"{capture}: camera from its metadata, main lens focused at infinity (the metadata has no "
                 f"focus distance); for other settings pass `camera=`")
            return built.camera
    raise LfprocError("decoding a capture needs `camera=` (a Camera or a camera TOML file); only Lytro files carry "
                      "their camera in their metadata")


class _warnings_said_once:
    """Warnings inside, as :class:`LfprocWarning` (a library's own category) whatever they were raised as, each
    text once, at the caller's line."""

    def __enter__(self):
        self._catcher = warnings.catch_warnings(record=True)
        self._caught = self._catcher.__enter__()
        warnings.simplefilter("always")
        return self

    def __exit__(self, *exc):
        self._catcher.__exit__(*exc)
        said = set()
        for w in self._caught:
            category = w.category if issubclass(w.category, LfprocWarning) else LfprocWarning
            if (str(w.message), category) not in said:
                said.add((str(w.message), category))
                warn(str(w.message), category)
        return False
