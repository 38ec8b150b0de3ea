"""The :class:`Decoder`: a white image's prepared state, and the decode of captures into views with it."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ..grid import LensGrid
from ._band import read_band, sensor_levels
from ._cells import cell_classes, cell_shares
from ._demosaic import channel_count, check_cfa, check_method
from ._hexagonal import check_hex_size, hex_rows_to_rect, rect_grid_of, rect_row_count
from ._inverse_white import inverse_white
from ._plan import ReadPlan, plan_reading
from ._positions import check_m_hat
from ._resample import check_remap_size, cv_flag
from ._rim_demosaic import balanced_white
from ._view_mask import carrying_views, view_sampling
from ._whole_lenses import crop_to_whole_lenses

#: decode Bayer mosaics rim-aware (:mod:`._rim_demosaic`): every view read like a mono sensor's
RIM_AWARE = True


@dataclass(frozen=True, eq=False)
class Decoder:
    """Decodes captures that share one white image and grid (see :mod:`lfproc.decode`).

    Build it with :func:`make_decoder`; call it on a sensor image to get the views.
    """

    grid: LensGrid               # the lenses decoded: the input grid cropped to whole lenses
    m_hat: int
    cfa: str
    interpolation: str
    demosaic_method: str
    sensor_shape: tuple          # (H, W) of the white image, which every capture must share
    channels: int
    inverse_white: np.ndarray    # (m̂, m̂, rows, cols, C or 1) on ``grid``: 1 / white views where delivered, else 0
    output_grid: LensGrid        # lens positions of the decoded light field (rectangular, also for hex input)
    views_delivered: np.ndarray = None   # (m̂, m̂) bool: the views that are not 0 everywhere
    view_shift_px: np.ndarray = None     # (m̂, m̂, 2) sensor px (x, y) each view's samples sit off nominal, or None
    cells: np.ndarray = None             # (H, W) uint8 lens class of each pixel (own-cell reading), or None
    view_centre: tuple = None            # (c_y, c_x) samples: the central view read off the lens centres, or None
    balanced_white: np.ndarray = None    # (H, W) float32 white per Bayer phase level (rim-aware decoding), or None
    phase_levels: np.ndarray = None      # (4,) the Bayer phases' bright levels (rim-aware decoding), or None
    border_class: np.ndarray = None      # (H, W) uint8 class of the lens across the nearest cell border, or None
    border_share: np.ndarray = None      # (H, W) uint8 each pixel's share in its own lens (128 … 255), or None

    @property
    def rim(self) -> tuple | None:
        """``(balanced white, phase levels)`` of rim-aware Bayer decoding (:mod:`._rim_demosaic`), or None."""
        return None if self.balanced_white is None else (self.balanced_white, self.phase_levels)

    @property
    def shares(self) -> tuple | None:
        """``(border class, border share)`` (:func:`._cells.cell_shares`), or None (hard cell borders)."""
        return None if self.border_class is None else (self.border_class, self.border_share)

    def __call__(self, sensor: np.ndarray, cfa: str | None = None) -> np.ndarray:
        """Views ``(m̂, m̂, Ny, Nx, C)`` float32 of one sensor image.

        ``cfa`` is the capture's colour filter when known: it must be the white image's.
        """
        sensor = np.asarray(sensor)
        if sensor.shape[:2] != self.sensor_shape:
            raise LfprocError(f"capture is {sensor.shape[1]}x{sensor.shape[0]} px but the white image is "
                              f"{self.sensor_shape[1]}x{self.sensor_shape[0]}; use the white image of the same camera")
        if cfa is not None and cfa != self.cfa and sensor.ndim == 2:
            raise LfprocError(f"capture has colour filter {cfa} but the white image has {self.cfa}; "
                              f"use a white image of the same camera and mode")
        if np.issubdtype(sensor.dtype, np.floating) and not np.all(np.isfinite(sensor)):
            raise LfprocError("the capture contains NaN or infinite pixels; replace them (e.g. numpy.nan_to_num) "
                              "before decoding")
        if channel_count(sensor, self.cfa) != self.channels:
            raise LfprocError(f"capture has {channel_count(sensor, self.cfa)} channels but the white image has "
                              f"{self.channels}; use a white image taken with the same camera settings")
        plan = self.read_plan
        # zeros: only the runs of delivered views are computed, the others are never touched (nor paged in)
        out = np.zeros((self.m_hat, self.m_hat, self.output_grid.rows, self.output_grid.cols, self.channels),
                       dtype=np.float32)
        scratch = {}   # the bands share their scratch memory (see _band.borrowed)
        levels = sensor_levels(plan, sensor)
        for band in plan.bands:
            read_band(plan, band, sensor, scratch, functools.partial(self._devignette, out, band.rows, band.out_rows),
                      levels)
        return out

    @functools.cached_property
    def read_plan(self) -> ReadPlan:
        """How captures are read (:class:`._plan.ReadPlan`): built on first use, then kept."""
        return plan_reading(self.grid, self.m_hat, self.sensor_shape, self.cfa, self.demosaic_method,
                            self.interpolation, self.channels, shift=self.view_shift_px, cells=self.cells,
                            shares=self.shares, rim=self.rim, delivered=self.views_delivered, to_rect=True)

    def _devignette(self, out: np.ndarray, rows: range, out_rows: range, ky: int, kx0: int, kx1: int,
                    run: np.ndarray) -> None:
        """Devignette a run of raw views of lens ``rows`` (:func:`._band.read_band`'s ``sink``) into
        ``out[..., out_rows]`` (resampled to rectangular rows on a hexagonal grid)."""
        run *= self.inverse_white[ky:ky + 1, kx0:kx1, rows.start:rows.stop]
        dst = out[ky:ky + 1, kx0:kx1, out_rows.start:out_rows.stop]
        if self.grid.kind == "hexagonal":
            hex_rows_to_rect(run, rows.start, out_rows, dst)
        else:
            dst[...] = run


def make_decoder(white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str = "none", *,
                 interpolation: str = "linear", demosaic_method: str = "fast",
                 dark_fraction: float = 0.05, centroid_tolerance: float | None = 0.1,
                 whole_lenses: bool = True) -> Decoder:
    """Prepare a :class:`Decoder`: the views it delivers, the lenses it keeps, the white's inverse views.

    Parameters
    ----------
    white : ndarray
        White image (linear), ``(H, W)`` mosaic/mono or ``(H, W, C)``.
    grid : LensGrid
        Fitted lattice (``lfproc.calibrate.estimate_grid``).
    m_hat : int
        Odd micro image size after resampling (``camera.m_hat``).
    cfa : str
        Bayer pattern of 2-D mosaics, or ``"none"``.
    dark_fraction : float
        Samples whose white value is below this fraction of the white's bright level (its 99th
        percentile) in any channel carry no signal and decode to 0 in every channel.
    demosaic_method : str
        Bayer mosaics: ``"fast"`` decodes rim-aware (:mod:`._rim_demosaic`: every channel at the pixel's
        own ray, the hue from its micro image; the outer views are delivered), ``"careful"`` demosaics
        each lens class's cells with OpenCV's edge-aware method.
    centroid_tolerance : float or None
        A view is delivered only where it is lit at its nominal position and its samples' white-weighted
        centroid lies (at nominal, or read further out: :mod:`lfproc.decode._view_mask`) within this many
        effective pixels of its nominal position; every lens is read from its own cell. Other views are 0.
        ``None`` reads every view at nominal from the plain sensor image and delivers all of them (the
        old decoder: biased parallax and crosstalk at the micro image edges, views in the gaps).
    whole_lenses : bool
        Crop the grid to the lenses whose delivered samples all lie on the sensor (default); ``False``
        keeps every lens of ``grid`` (partial lenses then read 0 past the sensor border).
    """
    m_hat = check_m_hat(m_hat)
    if not 0 <= dark_fraction < 1:
        raise LfprocError(f"dark_fraction must be in [0, 1), got {dark_fraction}")
    if centroid_tolerance is not None and not centroid_tolerance > 0:
        raise LfprocError(f"centroid_tolerance must be a positive number of effective pixels or None, "
                          f"got {centroid_tolerance}")
    check_cfa(cfa)
    check_method(demosaic_method)
    cv_flag(interpolation)
    white = np.asarray(white)
    if not np.all(np.isfinite(white)):  # before demosaicing, which would report the mosaic instead
        raise LfprocError("the white image contains NaN or infinite pixels; use a clean white image")
    check_remap_size(white.shape[0], white.shape[1], grid.cols)
    rim = None
    if RIM_AWARE and centroid_tolerance is not None and white.ndim == 2 and cfa != "none" and (
            demosaic_method == "fast"):
        rim = balanced_white(white, dark_fraction)
    if centroid_tolerance is None:
        delivered, shift, cells, view_centre = np.ones((m_hat, m_hat), dtype=bool), None, None, None
    else:
        sampling = view_sampling(white, grid, m_hat, cfa, demosaic_method, interpolation, centroid_tolerance,
                                 probe_white=None if rim is None else rim[0])
        delivered, shift = sampling.delivered, sampling.shift_px
        view_centre = centre_in_samples(sampling.centre_offset_px, grid, m_hat) if sampling.centred else None
    if whole_lenses:
        grid = crop_to_whole_lenses(grid, m_hat, delivered, white.shape, shift)
    if grid.kind == "hexagonal":
        check_hex_size(grid.rows, grid.cols)
    shares = None
    if centroid_tolerance is not None:
        cells = cell_classes(grid, white.shape)
        if rim is not None:
            shares = cell_shares(grid, white.shape, classes=cells)
    # the white is read as the captures will be, rim-aware decoding's balanced white like a mono image
    read = white if rim is None else rim[0]
    plan = plan_reading(grid, m_hat, white.shape, cfa if rim is None else "none", demosaic_method, interpolation,
                        channel_count(read, cfa if rim is None else "none"), shift=shift, cells=cells, shares=shares)
    inverse, signal = inverse_white(read, plan, dark_fraction, delivered)
    if centroid_tolerance is not None:     # a view is delivered only where its samples really carry signal
        kept = carrying_views(signal, delivered)
        inverse[~kept] = 0.0
        delivered = kept
    output_grid = rect_grid_of(grid) if grid.kind == "hexagonal" else grid
    assert grid.kind != "hexagonal" or output_grid.rows == rect_row_count(grid.rows)
    balanced, levels = rim if rim is not None else (None, None)
    border_class, border_share = shares if shares is not None else (None, None)
    return Decoder(grid, m_hat, cfa, interpolation, demosaic_method, tuple(white.shape[:2]),
                   channel_count(white, cfa), inverse, output_grid, delivered, shift, cells, view_centre,
                   balanced, levels, border_class, border_share)


def centre_in_samples(offset_px, grid: LensGrid, m_hat: int) -> tuple:
    """A sensor offset (x, y) px as (c_y, c_x) samples (pitch/m̂) along the lattice's v and u axes."""
    u, v = grid.axes
    step = grid.pitch_px / m_hat
    x, y = float(offset_px[0]), float(offset_px[1])
    return (x * v[0] + y * v[1]) / step, (x * u[0] + y * u[1]) / step


def decode(sensor: np.ndarray, white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str = "none", **options):
    """Decode one sensor image into views ``(m̂, m̂, Ny, Nx, C)``; see :func:`make_decoder` for options."""
    return make_decoder(white, grid, m_hat, cfa, **options)(sensor)


def decode_capture(capture, white, grid: LensGrid, camera, **options):
    """Decode a :class:`lfproc.io.Capture` with its white image into a :class:`~lfproc.LightField`."""
    from ..lightfield import LightField

    decoder = make_decoder(white.data, grid, camera.m_hat, white.cfa, **options)
    try:
        views = decoder(capture.data, capture.cfa)
    except LfprocError as exc:
        raise LfprocError(f"{capture.source}: {exc.marked}") from None
    return LightField.from_views(views, camera, decoder.output_grid, decoder.views_delivered, decoder.view_centre)
