"""From files to light fields: the steps every command shares (camera, lens grid, white image, decoder).

``--white WHITE`` calibrates the grid from the white image and devignettes with it; ``--calib GRID.json``
reads a grid written by ``lfproc calibrate`` and devignettes with the white image recorded in it (if
that file still exists); both together use the given grid and the given white image. Without any
white image the captures are decoded without devignetting, and a warning says so.

Lytro captures: ``--white-dir DIR`` picks the white image of the first capture's camera (serial) with
the nearest zoom and focus steps from a calibration folder and says which on stderr; a Lytro white
image of another camera or zoom is refused, for the first capture before any work and for every
later one before it is decoded. Without a camera file, the camera comes from the first capture's
metadata (`camera_for_captures`).
"""

from __future__ import annotations

import json
import os
import sys
import warnings
from dataclasses import dataclass, field

import numpy as np

from .camera import Camera
from .errors import LfprocError
from .grid import LensGrid
from .lightfield import LightField


@dataclass(frozen=True, eq=False)
class DecodeSetup:
    """Everything needed to decode captures of one camera: the camera, its grid and white image."""

    camera: Camera
    grid: LensGrid
    white: object | None          # lfproc.io.Capture or None
    interpolation: str = "linear"
    demosaic_method: str = "fast"
    white_metadata: object | None = None   # lfproc.io.LytroMetadata of a Lytro white image, else None
    _decoders: dict = field(default_factory=dict, repr=False)

    def decoder_for(self, shape: tuple, cfa: str):
        """The (cached) decoder for captures of this sensor shape and CFA.

        With a white image there is one decoder (it rejects captures of another size or CFA);
        without one, a flat white of each capture's shape stands in.
        """
        from .decode import make_decoder

        key = "white" if self.white is not None else (tuple(shape[:2]), cfa)
        if key not in self._decoders:
            if self.white is not None:
                white, white_cfa = self.white.data, self.white.cfa
            else:
                white, white_cfa = np.ones(shape, np.float32), cfa  # the capture's own shape and channels
            self._decoders[key] = make_decoder(white, self.grid, self.camera.m_hat, white_cfa,
                                               interpolation=self.interpolation,
                                               demosaic_method=self.demosaic_method)
        return self._decoders[key]


def read_grid(path: str) -> tuple[LensGrid, str | None]:
    """A GRID.json written by ``lfproc calibrate``: the grid and the white image it recorded (or None)."""
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except FileNotFoundError:
        raise LfprocError(f"{path}: grid file not found; run 'lfproc calibrate WHITE --camera CAM -o {path}'") \
            from None
    except (OSError, ValueError) as exc:
        raise LfprocError(f"{path}: not a readable grid file ({exc}); run lfproc calibrate again") from None
    if not isinstance(data, dict):
        raise LfprocError(f"{path}: not a grid file written by 'lfproc calibrate'; run lfproc calibrate again")
    return LensGrid.from_json_dict(data, source=path), data.get("white_image")


def calibrate_white(white, camera: Camera) -> LensGrid:
    """Fit the lens grid to a white :class:`~lfproc.io.Capture`; what ``lfproc calibrate`` would warn about
    (an untrustworthy fit, scene texture, an exit pupil the camera file contradicts) is warned here too."""
    from .calibrate import exit_pupil_warning, find_grid, implied_exit_pupil

    estimate = find_grid(white.data, kind=camera.grid, approx_pitch_px=camera.pitch_px, cfa=white.cfa,
                         source=white.source)
    pupil = implied_exit_pupil(estimate.grid.pitch_px, estimate.pitch_sigma_px, camera)
    for line in filter(None, (*estimate.warnings,
                              exit_pupil_warning(white.source, pupil, camera))):
        warnings.warn(line.replace(": warning: ", ": ", 1), stacklevel=2)
    return estimate.grid


def prepare_decoding(camera: Camera, calib: str | None = None, white: str | None = None, *,
                     interpolation: str = "linear", demosaic_method: str = "fast",
                     grid: LensGrid | None = None, white_dir: str | None = None,
                     captures: tuple | list = ()) -> DecodeSetup:
    """Resolve ``--calib``/``--white``/``--white-dir`` into a :class:`DecodeSetup` (see the module docstring).

    ``grid``, when given, is the grid these files were already calibrated to (by another process):
    it is used as is, and the white image is only read for devignetting. ``captures`` are the inputs
    to decode: ``white_dir`` picks the white image for the first of them, and a Lytro white image is
    checked against it (same camera and zoom) before anything is calibrated.
    """
    from .io import read_capture

    if white is not None and white_dir is not None:
        raise LfprocError("give --white WHITE or --white-dir DIR, not both")
    if calib is None and white is None and white_dir is None:
        raise LfprocError("give --white WHITE (a white image), --white-dir DIR (a Lytro calibration folder) or "
                          "--calib GRID.json (from lfproc calibrate)")
    first = _lytro_metadata_of(captures[0]) if captures else None
    if white_dir is not None:
        white = _white_from_folder(white_dir, first, captures[0] if captures else None)
    recorded_white = None
    known_grid = grid
    if calib is not None:
        grid, recorded_white = read_grid(calib)
    white_path = white or (recorded_white if recorded_white and os.path.exists(recorded_white) else None)
    white_metadata = _lytro_metadata_of(white_path) if white_path else None
    if white_metadata is not None and white_metadata.modulation_frame is False:
        print(f"lfproc: warning: {white_path}: its metadata marks it as a capture, not a white image "
              f"(modulationFrame false); pass a white image from the camera's calibration folder", file=sys.stderr)
    if first is not None and white_metadata is not None:
        from .io import check_white_matches
        check_white_matches(first, white_metadata)
    white_capture = read_capture(white_path, camera) if white_path else None
    if known_grid is not None:
        grid = known_grid
    elif calib is None:
        grid = calibrate_white(white_capture, camera)
    elif white_capture is None:
        warnings.warn(f"{calib}: no white image available (recorded: {recorded_white}); decoding without "
                      f"devignetting — pass --white WHITE to correct vignetting", stacklevel=2)
    return DecodeSetup(camera, grid, white_capture, interpolation, demosaic_method, white_metadata)


def _lytro_metadata_of(path: str):
    """The Lytro metadata of ``path``, or None for files that are not Lytro files."""
    from .io import is_lytro_file, read_lytro_metadata

    if path is None or not os.path.isfile(path) or not is_lytro_file(path):
        return None
    return read_lytro_metadata(path)


def _white_from_folder(folder: str, capture_metadata, capture_path) -> str:
    from .io import pick_white_image

    if capture_metadata is None:
        raise LfprocError(f"--white-dir {folder}: picks a white image by the metadata of Lytro captures, but "
                          f"{capture_path or 'no capture'} is not a Lytro file; pass --white WHITE instead")
    choice = pick_white_image(capture_metadata, folder)
    print(f"lfproc: {choice.reason}", file=sys.stderr)
    return choice.path


def white_image_for(captures, white: str | None = None, white_dir: str | None = None) -> str | None:
    """``--white`` as given, or the white image ``--white-dir`` picks for the first capture (said on stderr)."""
    if white is not None and white_dir is not None:
        raise LfprocError("give --white WHITE or --white-dir DIR, not both")
    if white_dir is None:
        return white
    first = captures[0] if captures else None
    return _white_from_folder(white_dir, _lytro_metadata_of(first), first)


def camera_for_captures(camera_file: str | None, captures, focus_distance_mm: float | None = None) -> Camera:
    """The camera of ``--camera FILE``, or without one the camera in the first Lytro capture's metadata.

    The metadata has no focus distance: the main lens is taken as focused at infinity (or at
    ``focus_distance_mm``), and one line on stderr says so and how to fix it.
    """
    if camera_file is not None:
        return Camera.from_toml(camera_file)
    first = _lytro_metadata_of(captures[0]) if captures else None
    if first is None:
        where = f"{captures[0]}: " if captures else ""
        raise LfprocError(f"{where}decoding a capture needs --camera CAM (a camera TOML file); only Lytro files "
                          f"carry their camera in their metadata")
    from .io import lytro_camera

    built = lytro_camera(first, focus_distance_mm)
    focus = "focused at infinity (the metadata has no focus distance)" if focus_distance_mm is None else \
        f"focused at {focus_distance_mm:g} mm"
    print(f"lfproc: camera from {first.source}'s metadata (Lytro {first.model}), main lens {focus}; for other "
          f"settings write it with 'lfproc camera {first.source} -o camera.toml' and pass --camera",
          file=sys.stderr)
    return built.camera


def load_lightfield(path: str, setup: DecodeSetup) -> LightField:
    """Read and decode one capture (a Lytro capture is checked against a Lytro white image first)."""
    from .io import check_white_matches, is_lytro_file, read_capture, read_lytro

    if setup.white_metadata is not None and os.path.isfile(path) and is_lytro_file(path):
        capture, capture_metadata = read_lytro(path)
        check_white_matches(capture_metadata, setup.white_metadata)
    else:
        capture = read_capture(path, setup.camera)
    decoder = setup.decoder_for(capture.data.shape, capture.cfa)
    try:
        views = decoder(capture.data, capture.cfa)
    except LfprocError as exc:
        raise LfprocError(f"{path}: {exc}") from None
    return LightField.from_views(views, setup.camera, decoder.output_grid, decoder.views_delivered)


def output_stem(path: str) -> str:
    """The name outputs of a capture start with: its file name without extension (``.lfp.npz`` as one)."""
    name = os.path.basename(path)
    if name.lower().endswith(".lfp.npz"):
        return name[:-len(".lfp.npz")]
    return os.path.splitext(name)[0]


def unique_stems(paths: list[str]) -> dict[str, str]:
    """Map each input to its output stem; inputs whose names collide get their folder name prefixed."""
    stems = [output_stem(p) for p in paths]
    result = {}
    for path, stem in zip(paths, stems):
        if stems.count(stem) > 1:
            parent = os.path.basename(os.path.dirname(os.path.abspath(path))) or "root"
            stem = f"{parent}_{stem}"
        result[path] = stem
    if len(set(result.values())) != len(result):
        raise LfprocError("several inputs would write outputs of the same name; give each capture a distinct name")
    return result
