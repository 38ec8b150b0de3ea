"""The :class:`Decoder`: white-image devignetting and the banded decode of captures into views."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ..grid import LensGrid
from ._demosaic import (DEMOSAIC_REACH_PX, channel_count, check_cfa, check_method, demosaic_u16, quantize,
                        quantized_zero, to_channels)
from ._hexagonal import check_hex_size, hex_rows_read, hex_rows_to_rect, rect_grid_of, rect_row_count
from ._positions import check_m_hat, lens_centers, lens_offsets_px, sensor_rows_read
from ._resample import CV_MAX_SIZE, INTERPOLATION_REACH_PX, check_remap_size, cv_flag, remap_into
from ._cells import CLASSES, cell_classes, cell_shares, class_weight, lens_class, masked
from ._view_mask import carrying_views, central_range, view_sampling
from ._whole_lenses import crop_to_whole_lenses
from ._rim_demosaic import RATIO_FLOOR, RATIO_LIMIT, balanced_white, phase_channels

#: decode Bayer mosaics rim-aware (:mod:`._rim_demosaic`): every view read like a mono sensor's
RIM_AWARE = True

#: interpolations whose weights are >= 0 (each sample within its taps' range: safe on 16-bit data)
CONVEX_INTERPOLATIONS = ("nearest", "linear")
#: bytes of one band's float32 scratch views: small enough to stay cheap next to the output
BAND_BYTES = 32 * 2**20
#: samples of the white image's views used for its bright level (a strided subset beyond this)
LEVEL_SAMPLES = 4_000_000
#: a sample read from its own cell needs at least this share of its kernel on the cell's pixels
MIN_OWN_WEIGHT = 0.05


def _band_rows(m_hat: int, cols: int, channels: int) -> int:
    return max(2, BAND_BYTES // max(1, m_hat * m_hat * cols * channels * 4))


def view_runs(delivered) -> list[tuple[int, int, int]]:
    """``(ky, kx0, kx1)`` per view row with delivered views: the run from its first to its last one.

    Only these views are resampled and devignetted when a capture is decoded; the others are 0 and never
    computed (for a round aperture the runs hold about π/4 of the views of their bounding square)."""
    if delivered is None:
        return None
    runs = []
    for ky, row in enumerate(np.asarray(delivered, dtype=bool)):
        kx = np.flatnonzero(row)
        if kx.size:
            runs.append((ky, int(kx[0]), int(kx[-1]) + 1))
    return runs


def read_band(sensor: np.ndarray, grid: LensGrid, m_hat: int, rows: range, cfa: str, demosaic_method: str,
              interpolation: str, shift: np.ndarray | None = None, cells: np.ndarray | None = None,
              runs: list | None = None, scratch: dict | None = None, sink=None,
              rim: tuple | None = None, shares: tuple | None = None) -> np.ndarray | None:
    """The raw (not devignetted) views of lens ``rows``: ``(m̂, m̂, len(rows), cols, C)`` float32.

    Only the sensor strip those lenses read is converted (demosaiced): no full-size temporaries.
    ``shift`` moves each view's samples (:func:`view_offsets_px`); ``cells``, the sensor's lens class map
    (:mod:`._cells`), makes every lens read its own cell only (else the plain sensor image is read).
    With ``runs`` (:func:`view_runs`) only those views are read; the others are left undefined.
    ``scratch`` (a dict kept by the caller across bands) lends the result's and the stack's memory: the
    result is then valid until the next call with the same ``scratch``. With ``sink``, each run is handed
    to ``sink(ky, kx0, kx1, views)`` (``views``: ``(1, kx1 − kx0, len(rows), cols, C)``, valid during the
    call) as soon as it is read, while it is still in the processor's cache, and None is returned.
    """
    runs = [(ky, 0, m_hat) for ky in range(m_hat)] if runs is None else runs
    margin = DEMOSAIC_REACH_PX[demosaic_method] + INTERPOLATION_REACH_PX[interpolation] + 4
    y0, y1 = sensor_rows_read(grid, m_hat, rows, margin, sensor.shape[0], shift)
    channels = channel_count(sensor, cfa)
    n = len(rows)
    out = None if sink is not None else borrowed(scratch, "views", (m_hat, m_hat, n, grid.cols, channels),
                                                 np.float32)

    def target(ky, kx0, kx1):
        if out is not None:
            return flat_out(out, ky, kx0, kx1)
        return borrowed(scratch, "run", ((kx1 - kx0) * n, grid.cols, channels), np.float32)

    def deliver(ky, kx0, kx1, block):
        if sink is not None:
            sink(ky, kx0, kx1, block.reshape(1, kx1 - kx0, n, grid.cols, channels))

    if y1 <= y0:
        for ky, kx0, kx1 in runs:
            block = target(ky, kx0, kx1)
            block[...] = 0.0
            deliver(ky, kx0, kx1, block)
        return out
    reach = INTERPOLATION_REACH_PX[interpolation]     # a sample reads rows floor(y) - reach + 1 … floor(y) + reach
    gap = 2 * reach
    if cells is not None and CLASSES * (y1 - y0 + 2 * gap) >= CV_MAX_SIZE and n > 1:   # too tall for remap: halves
        half = rows.start + n // 2
        views = np.concatenate([read_band(sensor, grid, m_hat, part, cfa, demosaic_method, interpolation, shift,
                                          cells, runs) for part in (range(rows.start, half), range(half, rows.stop))],
                               axis=2)
        for ky, kx0, kx1 in runs:
            deliver(ky, kx0, kx1, views[ky, kx0:kx1])
        return None if sink is not None else views
    flag = cv_flag(interpolation)
    off_x, off_y = lens_offsets_px(grid, m_hat, rows, shift)
    centers = lens_centers(grid, rows).astype(np.float32)
    cx, cy = centers[None, :, :, 0], centers[None, :, :, 1] - np.float32(y0)

    def run_maps(ky, kx0, kx1):
        """The remap maps of views ``(ky, kx0:kx1)``, rows over (kx, r): :func:`band_maps`' run of them."""
        return ((cx + off_x[ky, kx0:kx1].astype(np.float32)).reshape(-1, grid.cols),
                (cy + off_y[ky, kx0:kx1].astype(np.float32)).reshape(-1, grid.cols))

    if cells is None:
        strip = np.ascontiguousarray(to_channels(sensor[y0:y1], cfa, demosaic_method))
        for ky, kx0, kx1 in runs:   # map rows run over (kx, r): a run of views is a block of map rows
            block = target(ky, kx0, kx1)
            remap_into(block, strip, *run_maps(ky, kx0, kx1), flag)
            deliver(ky, kx0, kx1, block)
        return out
    if rim is not None:
        stack, scale, low, zero = _rim_stack(sensor[y0:y1], rim[0][y0:y1], cells[y0:y1],
                                             tuple(a[y0:y1] for a in shares), cfa, rim[1], grid, y0, gap, scratch)
    else:
        stack, scale, low, zero = _class_stack(sensor[y0:y1], cells[y0:y1], cfa, demosaic_method, grid, rows,
                                               gap, interpolation in CONVEX_INTERPOLATIONS, scratch,
                                               None if shares is None else tuple(a[y0:y1] for a in shares))
    height = y1 - y0
    r, q = np.meshgrid(np.arange(rows.start, rows.stop), np.arange(grid.cols), indexing="ij")
    base = (gap + lens_class(r, q) * (height + 2 * gap)).astype(np.float32)   # each lens's strip in the stack
    clipped = y0 == 0 or y1 == sensor.shape[0]     # only there can samples reach past the strip's gap rows
    for ky, kx0, kx1 in runs:
        map_x, map_y = run_maps(ky, kx0, kx1)
        my = map_y.reshape(kx1 - kx0, n, grid.cols) + base
        if clipped:    # reading past the gap, a sample reads only 0 in its own strip: so it does here
            y = my - base
            my[(y < reach - 1 - gap) | (y >= height + gap - reach)] = -2 * gap - 2
        block = target(ky, kx0, kx1)
        remap_into(block, stack, map_x, my.reshape(-1, grid.cols), flag, scale=scale, offset=low, border=zero)
        deliver(ky, kx0, kx1, block)
    return out


def borrowed(scratch: dict | None, name: str, shape: tuple, dtype) -> np.ndarray:
    """An uninitialised array: ``scratch[name]``'s memory (grown when too small) reused, or new without
    ``scratch``. Reusing a band's buffers for the next band spares the kernel from mapping and zeroing
    fresh pages for each (a band's stack and views are tens of MB; system time was a third of decoding)."""
    size = int(np.prod(shape)) * np.dtype(dtype).itemsize
    if scratch is None:
        return np.empty(shape, dtype)
    if name not in scratch or scratch[name].nbytes < size:
        scratch[name] = np.empty(size, np.uint8)
    return scratch[name][:size].view(dtype).reshape(shape)


def flat_out(out: np.ndarray, ky: int, kx0: int, kx1: int) -> np.ndarray:
    """``out[ky, kx0:kx1]`` as map rows over (kx, r): ``((kx1 − kx0)·rows, cols, C)``."""
    m_hat, _, rows, cols, channels = out.shape
    return out.reshape(m_hat, m_hat * rows, cols, channels)[ky, kx0 * rows:kx1 * rows]


def _class_stack(raw: np.ndarray, classes: np.ndarray, cfa: str, demosaic_method: str, grid: LensGrid,
                 rows: range, gap: int, convex: bool = True,
                 scratch: dict | None = None, shares: tuple | None = None) -> tuple[np.ndarray, float | None, float, int]:
    """The sensor strip once per lens class, masked to that class's cells and converted to channels,
    stacked vertically (class c at rows ``gap + c·(h + 2·gap)``) with ``gap`` rows of 0 around each, so
    that one ``remap`` reads every lens from its own class's strip, as if from that strip alone.

    A Bayer mosaic is quantized once (:func:`quantize`) and its classes demosaiced straight into a
    uint16 stack: returns ``(stack, 1 / scale, low, zero)``, ``linear = value / scale + low`` (``zero``: the
    value that stands for 0, :func:`quantized_zero`, read outside the stack), so that only the resampled
    samples are converted to float (the remap rounds them to the 16-bit unit, as the mosaic was). Other
    images, and every image when the interpolation is not ``convex`` (its negative lobes over- and
    undershoot the 16-bit range), give a float32 linear stack and ``(stack, None, 0.0, 0)``.
    """
    height, width = raw.shape[:2]
    channels = channel_count(raw, cfa)
    present = set(np.unique(lens_class(*np.meshgrid(np.arange(rows.start, min(rows.start + 2, rows.stop)),
                                                    np.arange(min(2, grid.cols)), indexing="ij"))).tolist())
    quantized = raw.ndim == 2 and cfa != "none"
    assert shares is None or not quantized, "cell shares weigh float images only"
    if quantized:
        as_u16, low, scale = quantize(raw)
        zero = quantized_zero(low, scale)
    else:
        low, scale, zero = 0.0, None, 0
    stack = borrowed(scratch, "stack", (CLASSES * (height + 2 * gap), width, channels),
                     np.uint16 if quantized else np.float32)
    for cls in range(CLASSES):
        top = gap + cls * (height + 2 * gap)
        stack[top - gap:top] = zero
        stack[top + height:top + height + gap] = zero
        dst = stack[top:top + height]
        if cls not in present:
            dst[...] = zero
        elif quantized:
            demosaic_u16(masked(as_u16, classes, cls, zero), cfa, demosaic_method, dst=dst)
        elif shares is not None:
            weight = class_weight(classes, *shares, cls)
            dst[...] = to_channels(raw * (weight if raw.ndim == 2 else weight[..., None]), cfa, demosaic_method)
        else:
            dst[...] = to_channels(masked(raw, classes, cls), cfa, demosaic_method)
    if scale is None:
        return stack, None, 0.0, 0
    if not convex:
        linear = stack.astype(np.float32)
        linear *= np.float32(1.0 / scale)
        linear += np.float32(low)
        return linear, None, 0.0, 0
    return stack, 1.0 / scale, low, zero


def _rim_stack(raw, wb, classes, shares, cfa, levels, grid, y0, gap, scratch=None):
    """:func:`_class_stack` for rim-aware decoding (:mod:`._rim_demosaic`): each class's ``ŵ·rgb``, float32."""
    from ._rim_kernel import rim_stack

    height, width = raw.shape[:2]
    stack = borrowed(scratch, "stack", (CLASSES * (height + 2 * gap), width, 3), np.float32)
    u, v = grid.axes
    lattice = np.array([grid.origin_xy_px[0], grid.origin_xy_px[1], u[0], u[1], v[0], v[1], grid.pitch_px,
                        grid.row_spacing_px, 1.0 if grid.kind == "hexagonal" else 0.0])
    rim_stack(raw, wb, classes, shares[0], shares[1], (1.0 / np.asarray(levels, np.float64)),
              phase_channels(cfa).astype(np.int64), y0, lattice, gap, RATIO_FLOOR, RATIO_LIMIT, stack,
              borrowed(scratch, "own lens", (height, width), np.int32),
              borrowed(scratch, "other lens", (height, width), np.int32))
    return stack, None, 0.0, 0


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
        m, grid = self.m_hat, self.grid
        out_grid = self.output_grid
        # zeros: only the runs of delivered views are computed, the others are never touched (nor paged in)
        out = np.zeros((m, m, out_grid.rows, out_grid.cols, self.channels), dtype=np.float32)
        runs = view_runs(self.views_delivered)
        runs = [(ky, 0, m) for ky in range(m)] if runs is None else runs
        step = _band_rows(m, grid.cols, self.channels)
        scratch = {}   # the bands share their scratch memory (see borrowed)
        for r0 in range(0, out_grid.rows, step):
            out_rows = range(r0, min(r0 + step, out_grid.rows))
            rows = hex_rows_read(out_rows, grid.rows) if grid.kind == "hexagonal" else out_rows
            read_band(sensor, grid, m, rows, self.cfa, self.demosaic_method, self.interpolation,
                      self.view_shift_px, self.cells, runs, scratch, functools.partial(self._devignette, out, rows,
                                                                                       out_rows), self.rim,
                      self.shares)
        return out

    def _devignette(self, out: np.ndarray, rows: range, out_rows: range, ky: int, kx0: int, kx1: int,
                    run: np.ndarray) -> None:
        """Devignette a run of raw views of lens ``rows`` (:func:`read_band`'s ``sink``) into ``out[..., out_rows]``
        (resampled to rectangular rows on a hexagonal grid)."""
        run *= self.inverse_white[ky:ky + 1, kx0:kx1, rows.start:rows.stop]
        dst = out[ky:ky + 1, kx0:kx1, out_rows.start:out_rows.stop]
        if self.grid.kind == "hexagonal":
            hex_rows_to_rect(run, rows.start, out_rows, dst)
        else:
            dst[...] = run


def _inverse_white(white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str, demosaic_method: str,
                   interpolation: str, dark_fraction: float, delivered: np.ndarray, shift=None,
                   cells=None, shares=None) -> tuple[np.ndarray, np.ndarray]:
    """``(inverse, signal)``: 1 / white views where the white carries signal in every channel and the view is
    delivered, else 0; and the share of each view's samples that carry signal over the central 60 % of the
    lenses (:func:`carrying_views`).

    Reading own cells (``cells``), a sample's white is compared with the threshold per unit of its kernel's
    weight on its own cell: a view read near the micro image's edge puts little weight on the lit pixels
    but stands for them alone (the weight cancels in capture / white). With cell ``shares`` (rim-aware
    decoding) a sample below the threshold is not set to 0 but divided by the threshold: it fades out
    as its white does, so that a grid a hundredth of a pixel off does not switch it on or off.
    """
    channels = channel_count(white, cfa)
    inverse = np.empty((m_hat, m_hat, grid.rows, grid.cols, channels), dtype=np.float32)
    step = _band_rows(m_hat, grid.cols, channels)
    bands = [range(r0, min(r0 + step, grid.rows)) for r0 in range(0, grid.rows, step)]
    for rows in bands:
        inverse[:, :, rows.start:rows.stop] = read_band(white, grid, m_hat, rows, cfa, demosaic_method,
                                                        interpolation, shift, cells, shares=shares)
    flat = inverse.reshape(-1)
    subset = flat[::max(1, flat.size // LEVEL_SAMPLES)]
    bright = float(np.percentile(subset, 99)) if subset.size else 0.0
    if not bright > 0:
        raise LfprocError("the white image is black at every lens centre; check the white image and the grid")
    threshold = np.float32(dark_fraction * bright)
    ones = None if cells is None else np.broadcast_to(np.float32(1.0), white.shape)   # no full-size copy
    counted = np.zeros((m_hat, m_hat))
    (r0, r1), (q0, q1) = central_range(grid.rows), central_range(grid.cols)
    for rows in bands:
        band = inverse[:, :, rows.start:rows.stop]
        weight = None if cells is None else read_band(ones, grid, m_hat, rows, cfa, demosaic_method,
                                                      interpolation, shift, cells, shares=shares)
        for ky in range(m_hat):      # per view row: the boolean temporaries stay small
            w = band[ky]
            # a sample carries signal only where every channel does: one dark channel alone would turn a
            # neutral sample magenta or green
            lit = w > threshold if weight is None else (weight[ky] > MIN_OWN_WEIGHT) & (w > threshold * weight[ky])
            all_lit = lit.all(axis=-1)
            inner = all_lit[:, max(r0 - rows.start, 0):max(r1 - rows.start, 0), q0:q1]
            counted[ky] += inner.sum(axis=(1, 2))
            if shares is not None:     # fade out below the threshold (continuous in the grid)
                floor = threshold * weight[ky]
                signal = floor > 0
                np.divide(np.float32(1.0), np.maximum(w, floor), out=w, where=signal)
                w[~signal] = 0.0
                continue
            signal = np.broadcast_to(all_lit[..., None], w.shape)
            np.divide(np.float32(1.0), w, out=w, where=signal)
            w[~signal] = 0.0
    inverse[~delivered] = 0.0
    return inverse, counted / max(1, (r1 - r0) * (q1 - q0))



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
    if rim is None:
        inverse, signal = _inverse_white(white, grid, m_hat, cfa, demosaic_method, interpolation, dark_fraction,
                                         delivered, shift, cells)
    else:
        inverse, signal = _inverse_white(rim[0], grid, m_hat, "none", demosaic_method, interpolation, dark_fraction,
                                         delivered, shift, cells, shares)
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
        raise LfprocError(f"{capture.source}: {exc}") from None
    return LightField.from_views(views, camera, decoder.output_grid, decoder.views_delivered, decoder.view_centre)
