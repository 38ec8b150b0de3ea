"""A decoding setup: what decodes every capture of one camera, made once by :func:`lfproc.prepare_decoding`
(``_prepare``) and used for many captures (:meth:`DecodeSetup.decode`).

The decoder derived from the white image (the views it delivers, the white image's resampled inverse) is
kept in the setup once made, and in the decoder cache on disk where asked (``cache=True``, the commands;
:mod:`lfproc.decoder_cache`). The white image's pixels are not kept once the decoder holds what decoding
needs of them: a setup pickles small (a batch sends one to each worker) and reads the white image again
only if its decoder must be derived again.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import LfprocError

_PATH = (str, os.PathLike)


@dataclass(frozen=True, eq=False)
class DecodeSetup:
    """Everything needed to decode captures of one camera: made by :func:`lfproc.prepare_decoding` after every
    input was checked, used by :meth:`decode` for each capture (the decoder derived once).

    Attributes
    ----------
    camera : Camera
        The camera, with the m̂ decoding uses (from the grid's measured pitch where the camera file states
        none; ``m_hat_note`` says why).
    grid : LensGrid
        The lens grid, with its calibration where known.
    white_path : str or None
        The white image that devignettes (None: no devignetting, or a white image given as an array).
    dark : lfproc.io.Capture or None
        The dark frame subtracted from every capture.
    reference : lfproc.inputs.ImageFacts or None
        The sensor size, channels and Bayer pattern every capture must have.
    inputs : dict
        Role → path of the files that shape every light field decoded (camera, grid, white, dark): their
        provenance.
    decode_interpolation, demosaic : str
        As :func:`lfproc.read_light_field`'s.
    cache : bool
        Keep the derived decoder in the decoder cache on disk and reuse it from there (docs/cache.md).
    white_note, m_hat_note : str or None
        One line each: which white image ``white_dir=`` picked and why; why m̂ differs from the camera
        file's (the commands print them; nothing is printed here).
    """

    camera: object
    grid: object
    white: object | None = field(default=None, repr=False)   # the white Capture while in memory, else None
    white_path: str | None = None
    dark: object | None = field(default=None, repr=False)
    reference: object | None = None
    inputs: dict = field(default_factory=dict)
    decode_interpolation: str = "linear"
    demosaic: str = "fast"
    cache: bool = False
    white_is_white: bool = False
    white_metadata: object | None = field(default=None, repr=False)   # a Lytro white image's metadata
    white_note: str | None = None
    m_hat_note: str | None = None
    _decoders: dict = field(default_factory=dict, repr=False)

    @property
    def has_white(self) -> bool:
        return self.white is not None or self.white_path is not None

    def decode(self, capture):
        """The light field of one capture, decoded with this setup.

        Parameters
        ----------
        capture : str, os.PathLike, ndarray or lfproc.io.Capture
            A capture file (any the commands read; a Lytro capture is checked against a Lytro white image)
            or its linear sensor values ``(H, W)`` (a Bayer mosaic of ``camera.cfa``) or ``(H, W, C)``.

        Returns
        -------
        LightField
            With the files it was decoded from in ``inputs`` (the capture's path, for provenance).

        Raises
        ------
        LfprocError
            A capture of another sensor size, channels or Bayer pattern than the white image, or a white
            image given as the capture (one line naming the capture).
        """
        from ..inputs import check_capture_is_not_white, subtract_dark
        from ..lightfield import LightField

        path = os.fspath(capture) if isinstance(capture, _PATH) else None
        capture = self._read(path) if path is not None else _as_capture(capture, self.camera)
        name = path if path is not None else capture.source
        self.check_capture(capture)
        capture = subtract_dark(capture, self.dark)
        decoder = self.decoder_for(capture.data.shape, capture.cfa)
        try:
            views = decoder(capture.data, capture.cfa)
        except LfprocError as exc:
            raise LfprocError(f"{name}: {exc.marked}") from None
        check_capture_is_not_white(name, views, decoder.views_delivered)
        inputs = dict(self.inputs) if path is None else {"capture": path, **self.inputs}
        return LightField.from_views(views, self.camera, decoder.output_grid, decoder.views_delivered,
                                     decoder.view_centre, inputs)

    def _read(self, path: str):
        """The capture file ``path`` (a Lytro capture checked against the Lytro white image first)."""
        from ..io import check_white_matches, is_lytro_file, read_capture, read_lytro

        if not os.path.isfile(path):
            raise LfprocError(_missing_capture(path))
        if self.white_metadata is not None and is_lytro_file(path):
            capture, metadata = read_lytro(path)
            check_white_matches(metadata, self.white_metadata)
            return capture
        return read_capture(path, self.camera)

    def decoder_for(self, shape: tuple, cfa: str):
        """The decoder for captures of this sensor shape and CFA: from this setup's memory, else from the
        decoder cache (``cache``), else derived. With a white image there is one decoder (it refuses captures
        of another size or CFA); without one, a flat white of each capture's shape stands in."""
        key = "white" if self.has_white else (tuple(shape[:2]), cfa)
        if key not in self._decoders:
            if self.cache:
                from ..decoder_cache import cached_decoder

                self._decoders[key] = cached_decoder(self._cache_key(shape, cfa),
                                                     lambda: self._make_decoder(shape, cfa))
            else:
                self._decoders[key] = self._make_decoder(shape, cfa)
        return self._decoders[key]

    def prepare(self) -> None:
        """Have the white image's decoder ready now: a bad white image fails before any capture is read, and a
        batch derives it once before its workers start."""
        if self.has_white:
            self.decoder_for((), "none")

    def check_capture(self, capture) -> None:
        """Refuse a capture whose size, channels or CFA differ from the white image's (or the grid's record)."""
        from ..inputs import ImageFacts, check_fits_grid_extent, check_same_sensor

        facts = ImageFacts.of_capture(capture)
        if self.reference is not None:
            check_same_sensor(facts, self.reference, "capture", reference_name(self.reference, self.grid))
        else:
            check_fits_grid_extent(facts, self.grid)

    def _make_decoder(self, shape: tuple, cfa: str):
        from ..decode import make_decoder

        if self.has_white:
            white = self.white if self.white is not None else self._read_white()
            data, white_cfa = white.data, white.cfa
        else:
            data, white_cfa = np.ones(shape, np.float32), cfa  # the capture's own shape and channels
        where = self.white_path or (self.white.source if self.white is not None else "the grid")
        try:
            decoder = make_decoder(data, self.grid, self.camera.m_hat, white_cfa,
                                   interpolation=self.decode_interpolation, demosaic_method=self.demosaic)
        except LfprocError as exc:
            if not self.has_white or str(exc).startswith(where):
                raise
            raise LfprocError(f"{where}: {exc.marked}") from None
        if not np.asarray(decoder.views_delivered).any():
            raise LfprocError(f"{where}: no view of its micro images can be decoded faithfully (no lit micro "
                              f"image where the grid puts one); pass the white image of this camera as `white=`")
        return decoder

    def _read_white(self):
        """The white image from its file, dark frame subtracted, checked to be a white image (not a capture
        of a scene) against the grid: what a decoder derived anew needs."""
        from ..inputs import check_white_is_white, subtract_dark
        from ..io import read_capture

        white = subtract_dark(read_capture(self.white_path, self.camera), self.dark, "white image")
        check_white_is_white(white.source, white.data, white.cfa, self.grid, white_is_white=self.white_is_white)
        return white

    def _cache_key(self, shape: tuple, cfa: str) -> str:
        from ..decoder_cache import array_digest, decoder_key, file_digest

        if self.white_path is not None:
            white = file_digest(self.white_path)
        elif self.white is not None:
            white = array_digest(self.white.data, self.white.cfa)
        else:
            white = f"flat {tuple(shape)} {cfa}"
        dark = None if self.dark is None else array_digest(self.dark.data, self.dark.cfa)
        return decoder_key(white=white, dark=dark, camera=self.camera, grid=self.grid,
                           interpolation=self.decode_interpolation, demosaic_method=self.demosaic)

    def __repr__(self) -> str:
        white = self.white_path or ("an array" if self.white is not None else "none")
        return (f"DecodeSetup({self.camera.name or self.camera.source or 'camera'}: {self.camera.m_hat}x"
                f"{self.camera.m_hat} views of {self.grid.rows} x {self.grid.cols} lenses, white image {white})")


def reference_name(reference, grid) -> str:
    """How messages name what every capture must match: the white image, or the one the grid file recorded."""
    recorded = (grid.calibration.white_facts or {}) if grid.calibration is not None else {}
    if grid.source is not None and reference.path in (recorded.get("path"), grid.source):
        return f"white image that {grid.source} was calibrated on"
    return "white image"


def camera_file(camera) -> str | None:
    """The camera file ``camera`` was read from (its provenance: a TOML file or napari-LF's metadata), or None
    (built in Python, from a Lytro capture's metadata, or carried by a saved light field)."""
    from ..io import is_napari_metadata

    source = getattr(camera, "source", None)
    if not source or not os.path.isfile(source):
        return None
    return source if str(source).lower().endswith(".toml") or is_napari_metadata(source) else None


def _missing_capture(path: str) -> str:
    if os.path.isdir(path):
        return (f"{path}: is a folder, not a capture file; pass one capture, or `for many make one setup "
                f"with lfproc.prepare_decoding(camera, white=...) and call its .decode(path) for each file`")
    return f"{path}: no such file; check the path"


def _as_capture(value, camera):
    from ._read import _capture

    return _capture(value, camera, "capture")
