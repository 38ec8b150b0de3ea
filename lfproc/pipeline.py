"""From files to light fields: the steps every command shares (camera, lens grid, white image, decoder).

``white`` (a white image) calibrates the grid and devignettes; ``grid`` (a GRID.json written by ``lfproc
calibrate``, the commands' ``--calib``) is used as it is and devignettes with the white image recorded in it
(if that file still exists); both together use the given grid and the given white image. Without any
white image the captures are decoded without devignetting, and a warning says so. ``dark`` (a dark frame) is
subtracted from the white image and every capture; a grid calibrated with one records it, and reading that
grid subtracts it again (`lfproc.inputs`, docs/inputs.md).

Before anything is read in full, camera, grid, white image, dark frame and captures are checked against
each other (lattice kind, micro image pitch, sensor size, Bayer pattern) and every input's header is
read; a capture given as the white image and a white image given as the capture are refused.

Lytro captures: ``white_dir`` picks the white image of the first capture's camera with the nearest zoom
and focus steps (named in ``DecodeSetup.white_note``; this module prints nothing); a Lytro white image
of another camera or zoom is refused. The camera from metadata: `lfproc.cli.lytro_defaults`.

Messages name the Python arguments (``white=``, ``grid=``, ``dark=``, ``white_dir=``); the commands word
them with their flags (`lfproc.cli.words`).
"""

from __future__ import annotations

import dataclasses
import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from .camera import Camera
from .errors import LfprocError, LfprocWarning
from .grid import LensGrid
from .lightfield import LightField


@dataclass(frozen=True, eq=False)
class DecodeSetup:
    """Everything needed to decode captures of one camera: the camera, its grid and white image.

    ``record`` (an `lfproc.inputs.GridRecord`) says what the grid was made from, ``dark`` is the dark
    frame (`lfproc.io.Capture`) that is subtracted from the white image and every capture, and
    ``reference`` (`lfproc.inputs.ImageFacts`) the sensor size and CFA every capture must have. ``white``
    is the white image (dark frame subtracted) where it was read already (to calibrate) or None;
    ``white_path`` its file, read only when the decoder's prepared state is not in the decoder cache
    (:mod:`lfproc.decoder_cache`).
    """

    camera: Camera
    grid: LensGrid
    white: object | None          # lfproc.io.Capture or None
    interpolation: str = "linear"
    demosaic_method: str = "fast"
    white_metadata: object | None = None   # lfproc.io.LytroMetadata of a Lytro white image, else None
    _decoders: dict = field(default_factory=dict, repr=False)
    record: object | None = None           # lfproc.inputs.GridRecord
    dark: object | None = None             # lfproc.io.Capture of the dark frame
    reference: object | None = None        # lfproc.inputs.ImageFacts every capture must match
    white_path: str | None = None
    cache: bool = True                     # keep derived decoders in the decoder cache (lfproc.decoder_cache)
    inputs: dict = field(default_factory=dict)   # role -> path of the files that shape every light field
    white_is_white: bool = False           # the user says the white image is one: no scene check
    m_hat_note: str | None = None          # why m̂ differs from the camera file's nominal one (lfproc.inputs.measured_m_hat)
    white_note: str | None = None          # which white image white_dir picked, and why (the commands print it)

    @property
    def has_white(self) -> bool:
        return self.white is not None or self.white_path is not None

    def decoder_for(self, shape: tuple, cfa: str):
        """The decoder for captures of this sensor shape and CFA, from this setup's memory, else from
        the decoder cache, else derived (and cached).

        With a white image there is one decoder (it rejects captures of another size or CFA);
        without one, a flat white of each capture's shape stands in.
        """
        key = "white" if self.has_white else (tuple(shape[:2]), cfa)
        if key not in self._decoders:
            if not self.cache:
                self._decoders[key] = self._make_decoder(shape, cfa)
                return self._decoders[key]
            from .decoder_cache import cached_decoder

            self._decoders[key] = cached_decoder(self._cache_key(shape, cfa), lambda: self._make_decoder(shape, cfa))
        return self._decoders[key]

    def prepare(self) -> None:
        """Have the white image's decoder ready now (from the cache, or derived and cached): a batch does
        this once before its workers start, and a bad white image fails before any capture is read."""
        if self.has_white:
            self.decoder_for((), "none")

    def _make_decoder(self, shape: tuple, cfa: str):
        from .decode import make_decoder

        if self.has_white:
            white = self.white if self.white is not None else self._read_white()
            data, white_cfa = white.data, white.cfa
        else:
            data, white_cfa = np.ones(shape, np.float32), cfa  # the capture's own shape and channels
        try:
            decoder = make_decoder(data, self.grid, self.camera.m_hat, white_cfa, interpolation=self.interpolation,
                                   demosaic_method=self.demosaic_method)
        except LfprocError as exc:
            if not self.has_white or str(exc).startswith(str(self.white_path or self.white.source)):
                raise
            raise LfprocError(f"{self.white_path or self.white.source}: {exc}") from None
        if not np.asarray(decoder.views_delivered).any():
            where = self.white_path or (self.white.source if self.white is not None else "the grid")
            raise LfprocError(f"{where}: no view of its micro images can be decoded faithfully (no lit micro "
                              f"image where the grid puts one); pass the white image of this camera as white=")
        return decoder

    def _read_white(self):
        """The white image from its file, dark frame subtracted, checked to be a white image (not a capture
        of a scene) against the grid it is used with: what a decoder derived anew needs."""
        from .inputs import check_white_is_white, subtract_dark
        from .io import read_capture

        white = subtract_dark(read_capture(self.white_path, self.camera), self.dark, "white image")
        check_white_is_white(white.source, white.data, white.cfa, self.grid, white_is_white=self.white_is_white)
        return white

    def _cache_key(self, shape: tuple, cfa: str) -> str:
        from .decoder_cache import array_digest, decoder_key, file_digest

        if self.white_path is not None:
            white = file_digest(self.white_path)
        elif self.white is not None:
            white = array_digest(self.white.data, self.white.cfa)
        else:
            white = f"flat {tuple(shape)} {cfa}"
        dark = None if self.dark is None else array_digest(self.dark.data, self.dark.cfa)
        return decoder_key(white=white, dark=dark, camera=self.camera, grid=self.grid,
                           interpolation=self.interpolation, demosaic_method=self.demosaic_method)

    def check_capture(self, capture) -> None:
        """Refuse a capture whose size, channels or CFA differ from the white image's (or the grid's record)."""
        from .inputs import ImageFacts, check_fits_grid_extent, check_same_sensor

        facts = ImageFacts.of_capture(capture)
        if self.reference is not None:
            check_same_sensor(facts, self.reference, "capture", _reference_name(self))
        elif self.record is not None:
            check_fits_grid_extent(facts, self.record)


def _reference_name(setup) -> str:
    if setup.white is not None and setup.reference is not None and setup.reference.path == setup.white.source:
        return "white image"
    return f"white image that {setup.record.path} was calibrated on" if setup.record is not None else "white image"


def calibrate_white(white, camera: Camera, record: bool = False, dark=None, *, white_is_white: bool = False):
    """Fit the lens grid to a white :class:`~lfproc.io.Capture`; what ``lfproc calibrate`` would warn about
    (an untrustworthy fit, an exit pupil the camera file contradicts) is warned here too, and a capture of a
    scene given as the white image is refused (`lfproc.inputs.check_white_is_white`; not with
    ``white_is_white``).

    With ``record``, returns an `lfproc.inputs.GridRecord` holding what the grid was made from (the white
    image's facts and hash, the ``dark`` frame's) instead of the bare `LensGrid`.
    """
    from .calibrate import exit_pupil_warning, find_grid, implied_exit_pupil
    from .inputs import check_white_is_white

    estimate = find_grid(white.data, kind=camera.grid, approx_pitch_px=camera.pitch_px, cfa=white.cfa,
                         source=white.source)
    check_white_is_white(white.source, white.data, white.cfa, estimate.grid, white_is_white=white_is_white,
                         texture=estimate.texture)
    pupil = implied_exit_pupil(estimate.grid.pitch_px, estimate.pitch_sigma_px, camera)
    for line in filter(None, (*estimate.warnings,
                              exit_pupil_warning(white.source, pupil, camera))):
        warnings.warn(line.replace(": warning: ", ": ", 1), LfprocWarning, stacklevel=2)
    if not record:
        return estimate.grid
    from .inputs import GridRecord, ImageFacts, file_hash, made_from

    facts = made_from(camera, ImageFacts.of_capture(white), file_hash(white.source),
                      None if dark is None else ImageFacts.of_capture(dark),
                      None if dark is None else file_hash(dark.source))
    return GridRecord(white.source, estimate.grid, os.path.abspath(white.source), facts, estimate.pitch_sigma_px)


def prepare_decoding(camera: Camera, calib: str | None = None, white: str | None = None, *,
                     interpolation: str = "linear", demosaic_method: str = "fast",
                     grid: LensGrid | None = None, white_dir: str | None = None,
                     captures: tuple | list = (), dark: str | None = None, cache: bool = True,
                     white_is_white: bool = False) -> DecodeSetup:
    """Resolve ``calib`` (a GRID.json; named ``grid=`` in messages, as in :func:`lfproc.read_light_field`),
    ``white``, ``white_dir`` and ``dark`` into a :class:`DecodeSetup` (module docstring).

    ``grid``, when given, is the grid these files were already calibrated to (by another process):
    it is used as is, and the white image is only read for devignetting. ``captures`` are the inputs
    to decode: ``white_dir`` picks the white image for the first of them, and a Lytro white image is
    checked against it (same camera and zoom) before anything is calibrated.

    ``cache``: keep the decoder derived from the white image in the decoder cache (on disk, docs/cache.md)
    and reuse it from there. ``setup.inputs`` names the files that shape every light field decoded with it
    (camera file, grid file, white image, dark frame: their provenance).

    Cheap checks come first (docs/inputs.md): the grid file is read and checked against the camera, the
    headers of the white image, the dark frame and the captures are read and checked against each other
    and the grid's record; only then is the white image read and calibrated. Without ``[decode] micro_image_px``
    in the camera file, m̂ comes from the grid's measured pitch (`lfproc.inputs.measured_m_hat`; the setup's
    ``camera`` carries it and ``m_hat_note`` says why). ``white_is_white``
    skips the check that the white image is not a capture of a scene (`lfproc.inputs.check_white_is_white`).
    """
    from .inputs import check_grid_fits_camera, check_same_sensor, probe_image, read_grid_record, reference_facts
    from .io import read_capture

    if white is not None and white_dir is not None:
        raise LfprocError("give white=... or white_dir=..., not both")
    if calib is None and white is None and white_dir is None:
        raise LfprocError("give white=... (a white image), white_dir=... (a Lytro calibration folder) or "
                          "grid=... (from lfproc calibrate)")
    first = lytro_metadata_of(captures[0]) if captures else None
    white_note = None
    if white_dir is not None:
        white, white_note = white_from_folder(white_dir, first, captures[0] if captures else None)
    record = read_grid_record(calib) if calib is not None else None
    if record is not None:
        check_grid_fits_camera(camera, record)
    white_path = white or _recorded_white(record)
    white_facts = probe_image(white_path, camera) if white_path else None
    recorded = reference_facts(record)
    if white_facts is not None and recorded is not None:
        check_same_sensor(white_facts, recorded, "white image", f"white image that {calib} was calibrated on")
    reference = white_facts or recorded
    dark_path = _dark_for(dark, record)
    if dark_path is not None:
        check_same_sensor(probe_image(dark_path, camera), reference, "dark frame", _name_of(reference, calib))
    _check_capture_headers(captures, camera, reference, record, calib)
    white_metadata = lytro_metadata_of(white_path) if white_path else None
    if white_metadata is not None and white_metadata.modulation_frame is False:
        warnings.warn(f"{white_path}: its metadata marks it as a capture, not a white image (modulationFrame "
                      f"false); pass a white image from the camera's calibration folder", LfprocWarning, stacklevel=2)
    if first is not None and white_metadata is not None:
        from .io import check_white_matches
        check_white_matches(first, white_metadata)
    # the expensive part: read the white image (to calibrate here, or on a decoder cache miss) and the dark frame
    from .inputs import read_dark, subtract_dark

    dark_capture = read_dark(dark_path, camera) if dark_path else None
    white_capture = None
    if grid is not None:
        record = record or _record_of(grid, white_path)
    elif record is None:
        white_capture = subtract_dark(read_capture(white_path, camera), dark_capture, "white image")
        record = calibrate_white(white_capture, camera, record=True, dark=dark_capture, white_is_white=white_is_white)
    elif white_path is None:
        warnings.warn(f"{calib}: no white image available (recorded: {record.white_image}); decoding without "
                      f"devignetting — pass white=... to correct vignetting", LfprocWarning, stacklevel=2)
    from .provenance import file_inputs

    inputs = file_inputs(camera=camera_file(camera), grid=calib, white=white_path, dark=dark_path)
    from .inputs import measured_m_hat

    used_grid = grid if grid is not None else record.grid
    measured = measured_m_hat(camera, used_grid.pitch_px, "calibration" if calib is None else calib)
    setup = DecodeSetup(measured.camera, used_grid, white_capture, interpolation,
                        demosaic_method, white_metadata, record=record, dark=dark_capture, reference=reference,
                        white_path=white_path, cache=cache, inputs=inputs, white_is_white=white_is_white,
                        m_hat_note=measured.note, white_note=white_note)
    setup.prepare()
    # the decoder holds what decoding needs of the white image: its pixels need not stay in memory (nor
    # travel to batch workers); the file is read again only if the decoder must be derived again
    return dataclasses.replace(setup, white=None) if white_path is not None else setup


def camera_file(camera) -> str | None:
    """The camera file ``camera`` was read from (its provenance: a TOML file or napari-LF's metadata), or None
    (built in Python, from a Lytro capture's metadata, or carried by a saved light field)."""
    from .io import is_napari_metadata

    source = getattr(camera, "source", None)
    if not source or not os.path.isfile(source):
        return None
    return source if str(source).lower().endswith(".toml") or is_napari_metadata(source) else None


def _record_of(grid, white_path):
    from .inputs import GridRecord

    return GridRecord(white_path if white_path is not None else "grid", grid)


def _name_of(reference, calib) -> str:
    if reference is None:
        return "white image"
    return "white image" if calib is None else f"white image that {calib} was calibrated on"


def _recorded_white(record) -> str | None:
    """The white image a grid file recorded, if it is still there with the content it was calibrated from."""
    from .inputs import same_file_content

    if record is None or not record.white_image or not os.path.exists(record.white_image):
        return None
    recorded_hash = (record.white_facts or {}).get("hash")
    if not same_file_content(record.white_image, recorded_hash):
        raise LfprocError(f"{record.white_image}: this white image, recorded in {record.path}, has changed since the "
                          f"grid was calibrated from it (its content hash differs); calibrate again, or pass "
                          f"white=... to devignette with it anyway")
    return record.white_image


def _dark_for(dark: str | None, record) -> str | None:
    """``dark`` as given, or the dark frame the grid file recorded; a different one is refused (one line)."""
    from .inputs import file_hash, same_file_content

    recorded = record.dark_facts if record is not None else None
    if dark is not None:
        if recorded and recorded.get("hash") and os.path.isfile(dark) and file_hash(dark) != recorded["hash"]:
            raise LfprocError(f"{dark}: this dark frame differs from the one {record.path} was calibrated with "
                              f"({recorded.get('path')}); pass that one, or calibrate again with dark={dark}")
        return dark
    if not recorded:
        return None
    path = recorded.get("path")
    if not path or not same_file_content(path, recorded.get("hash")):
        raise LfprocError(f"{record.path}: was calibrated with the dark frame {path}, which is missing or has "
                          f"changed since; pass the same dark frame with dark=..., or calibrate again")
    return path


def _check_capture_headers(captures, camera, reference, record, calib) -> None:
    """Every capture's header read and checked before the white image is calibrated; when none of them could
    be decoded, the first one's problem is the command's one error line (else each fails in its turn)."""
    from .inputs import check_fits_grid_extent, check_same_sensor, probe_image
    from .lightfield import is_lightfield_file

    errors = []
    paths = [p for p in captures if not is_lightfield_file(p)]
    for path in paths:
        try:
            facts = probe_image(path, camera)
            if reference is not None:
                check_same_sensor(facts, reference, "capture", _name_of(reference, calib))
            elif record is not None:
                check_fits_grid_extent(facts, record)
        except LfprocError as exc:
            errors.append(exc)
    if paths and len(errors) == len(paths):
        raise errors[0]


def lytro_metadata_of(path: str):
    """The Lytro metadata of ``path``, or None for files that are not Lytro files."""
    from .io import is_lytro_file, read_lytro_metadata

    if path is None or not os.path.isfile(path) or not is_lytro_file(path):
        return None
    return read_lytro_metadata(path)


def white_from_folder(folder: str, capture_metadata, capture_path) -> tuple[str, str]:
    """(path, reason): the white image of a Lytro calibration folder for a capture of that metadata (same
    camera, nearest zoom and focus steps), and one line saying which and why."""
    from .io import pick_white_image

    if capture_metadata is None:
        raise LfprocError(f"white_dir={folder}: picks a white image by the metadata of Lytro captures, but "
                          f"{capture_path or 'no capture'} is not a Lytro file; pass white=... instead")
    choice = pick_white_image(capture_metadata, folder)
    return choice.path, choice.reason


def load_lightfield(path: str, setup: DecodeSetup) -> LightField:
    """Read and decode one capture (a Lytro capture is checked against a Lytro white image first).

    Before decoding, the capture is checked against the white image (size, channels, CFA) and the dark frame
    is subtracted; after, a capture that is really a white image is refused (`lfproc.inputs`).
    """
    from .io import check_white_matches, is_lytro_file, read_capture, read_lytro

    if setup.white_metadata is not None and os.path.isfile(path) and is_lytro_file(path):
        capture, capture_metadata = read_lytro(path)
        check_white_matches(capture_metadata, setup.white_metadata)
    else:
        capture = read_capture(path, setup.camera)
    return decode_capture(capture, setup, path)


def decode_capture(capture, setup: DecodeSetup, path=None) -> LightField:
    """Decode one `lfproc.io.Capture` (read from ``path``, or an array when None) with ``setup``: checked
    against the white image, dark frame subtracted, decoded, and refused if it is really a white image."""
    from .inputs import check_capture_is_not_white, subtract_dark

    name = path if path is not None else capture.source
    setup.check_capture(capture)
    capture = subtract_dark(capture, setup.dark)
    decoder = setup.decoder_for(capture.data.shape, capture.cfa)
    try:
        views = decoder(capture.data, capture.cfa)
    except LfprocError as exc:
        raise LfprocError(f"{name}: {exc}") from None
    check_capture_is_not_white(name, views, decoder.views_delivered)
    inputs = dict(setup.inputs) if path is None else {"capture": path, **setup.inputs}
    return LightField.from_views(views, setup.camera, decoder.output_grid, decoder.views_delivered,
                                 decoder.view_centre, inputs)
