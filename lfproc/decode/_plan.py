"""The read plan: how a sensor image is read into raw views, band by band, decided once.

A decode reads the lenses in *bands* of lens rows, each from the sensor strip its samples reach
(demosaiced and, reading own cells, stacked once per lens class: :mod:`._band`), so that no temporary
is sensor-sized. A :class:`ReadPlan` holds everything that reading needs except the pixels: the grid,
m̂, the colour filter and methods, where the samples sit (``shift``), the cell map and border shares,
rim-aware decoding's balanced white, which views are read (``runs``), and the bands with their strips.
It is built once (:func:`plan_reading`) and every band is read from it alone.

The output does not depend on how the lenses are split into bands (:data:`BAND_BYTES` is memory tuning):

* a band's strip holds every pixel its samples read (their reach, demosaicing's and the interpolation's),
  and with rim-aware decoding every lit pixel of its lenses' cells (a lens's hue sums all of them);
* a band whose strip (or stack of four class strips) one ``cv2.remap`` would read over :data:`MAP_ROWS`
  rows is planned as smaller bands;
* the remap maps hold float32 positions, whose precision is relative: a row y read from a strip that
  starts at ``y0``, in the class strip at ``base``, is the float32 nearest to ``y − y0 + base``, which
  rounds differently for every band split (views up to 6e-4 apart on the bundled sample between one band
  and two lens rows a band). So each sample's row is rounded to :data:`MAP_STEP` px *on the sensor*, in
  float64, and only then moved (by even integers): below :data:`MAP_ROWS` every such value is a float32
  exactly, whatever the move, and bands are planned so that no map row reaches :data:`MAP_ROWS`. The
  columns are never moved: they are the float32 of the float64 position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..grid import LensGrid
from ._cells import CLASSES, SHARE_WIDTH_PX
from ._demosaic import DEMOSAIC_REACH_PX
from ._hexagonal import hex_rows_read, rect_row_count
from ._positions import lens_centers, lens_offsets_px, sensor_rows_read
from ._resample import CV_MAX_SIZE, INTERPOLATION_REACH_PX

#: bytes of one band's float32 scratch views: small enough to stay cheap next to the output
BAND_BYTES = 32 * 2**20
#: rows of the image one remap reads (a band's strip, or its stack of four class strips) stay below this
MAP_ROWS = 2 ** 12
#: the step (px) sample rows are rounded to on the sensor: the float32 spacing just below MAP_ROWS, so
#: that a float32 holds every multiple of it there (and rows err by at most 2⁻¹³ px, as float32 maps did
#: in a stack of 2048–4096 rows)
MAP_STEP = 2.0 ** -12


def band_rows(m_hat: int, cols: int, channels: int) -> int:
    """Lens rows per band: its views ``(m̂, m̂, rows, cols, C)`` float32 within :data:`BAND_BYTES` (at least 2)."""
    return max(2, BAND_BYTES // max(1, m_hat * m_hat * cols * channels * 4))


@dataclass(frozen=True)
class Band:
    """One band: lens ``rows`` of the grid read from sensor rows ``[y0, y1)``, written as ``out_rows``
    (the same rows, or rectangular rows of a hexagonal grid: :func:`lfproc.decode.hex_to_rect`)."""

    rows: range
    out_rows: range
    y0: int
    y1: int

    @property
    def height(self) -> int:
        return self.y1 - self.y0


@dataclass(frozen=True, eq=False)
class ReadPlan:
    """Everything reading a sensor image into raw views needs but the pixels (module docstring).

    ``cfa`` is the colour filter of the image read (``"none"`` for rim-aware decoding's balanced white,
    which is read like a mono image); ``cells`` the sensor's lens class map (own-cell reading, else the
    plain image is read); ``shares`` ``(border class, border share)`` (:func:`._cells.cell_shares`);
    ``rim`` ``(balanced white, phase levels)`` of rim-aware Bayer decoding; ``runs`` the
    ``(ky, kx0, kx1)`` runs of views read (the others are left undefined, or 0 in a decoder's output).
    """

    grid: LensGrid
    m_hat: int
    cfa: str
    demosaic_method: str
    interpolation: str
    sensor_shape: tuple
    channels: int
    bands: tuple
    runs: tuple
    shift: np.ndarray | None = None
    cells: np.ndarray | None = None
    shares: tuple | None = None
    rim: tuple | None = None

    @property
    def reach(self) -> int:
        """How far (px) the interpolation reads: a sample reads rows floor(y) − reach + 1 … floor(y) + reach."""
        return INTERPOLATION_REACH_PX[self.interpolation]

    @property
    def gap(self) -> int:
        """Rows of 0 around each class strip of a band's stack (even)."""
        return 2 * self.reach

    def positions(self, band: Band) -> tuple:
        """``(cx, cy, off_x, off_y)`` float64 of ``band``'s lenses: centres ``(1, rows, cols)`` and sample
        offsets broadcastable to ``(m̂, m̂, rows, cols)`` (:func:`._positions.lens_offsets_px`)."""
        off_x, off_y = lens_offsets_px(self.grid, self.m_hat, band.rows, self.shift)
        centres = lens_centers(self.grid, band.rows)
        return centres[None, :, :, 0], centres[None, :, :, 1], off_x, off_y

    def run_maps(self, positions: tuple, band: Band, ky: int, kx0: int, kx1: int) -> tuple:
        """The float32 remap maps of views ``(ky, kx0:kx1)`` of ``band`` in its strip, rows over (kx, r):
        rows rounded to :data:`MAP_STEP` on the sensor, then moved up by the strip's ``y0`` (module docstring)."""
        cx, cy, off_x, off_y = positions
        shape = (kx1 - kx0, len(band.rows), self.grid.cols)
        x = np.empty(shape, np.float32)
        np.add(cx, off_x[ky, kx0:kx1], out=x, casting="same_kind")    # the float32 of the float64 sum
        y = np.add(cy, off_y[ky, kx0:kx1], out=np.empty(shape))
        y *= 1.0 / MAP_STEP
        np.rint(y, out=y)
        y *= MAP_STEP
        y -= band.y0
        return x.reshape(-1, shape[2]), y.astype(np.float32).reshape(-1, shape[2])


def cell_reach_px(grid: LensGrid) -> float:
    """How far from its centre a lens's pixels (its cell and the border pixels it shares) reach: the cell's
    circumradius (√2/2 pitch rectangular, 1/√3 hexagonal) plus the border share's width, plus a pixel."""
    radius = grid.pitch_px * (1 / math.sqrt(3) if grid.kind == "hexagonal" else math.sqrt(0.5))
    return radius + SHARE_WIDTH_PX + 1.0


def _strip(grid: LensGrid, m_hat: int, rows: range, margin: int, height: int, shift, whole_cells: bool) -> tuple:
    """Sensor rows ``[y0, y1)`` (``y0`` even) that the samples of lens ``rows`` read, widened by ``margin``;
    with ``whole_cells`` also every pixel of those lenses' cells (rim-aware decoding sums them per lens)."""
    y0, y1 = sensor_rows_read(grid, m_hat, rows, margin, height, shift)
    if whole_cells:
        ys = lens_centers(grid, rows)[..., 1]
        reach = cell_reach_px(grid)
        y0 = min(y0, max(0, int(math.floor(float(ys.min()) - reach))) & ~1)
        y1 = max(y1, min(height, int(math.ceil(float(ys.max()) + reach)) + 1))
    return y0, max(y1, y0)


def plan_reading(grid: LensGrid, m_hat: int, sensor_shape: tuple, cfa: str, demosaic_method: str,
                 interpolation: str, channels: int, *, shift=None, cells=None, shares=None, rim=None,
                 delivered=None, to_rect: bool = False, rows_per_band: int | None = None) -> ReadPlan:
    """The :class:`ReadPlan` of reading images of ``sensor_shape`` along ``grid``.

    ``delivered`` (``(m̂, m̂)`` bool) limits the views read to :func:`view_runs` of it (all when None);
    ``to_rect`` plans the bands by the rectangular rows a hexagonal grid is resampled to (each band
    then reads the hexagonal rows those need); ``rows_per_band`` overrides :func:`band_rows` (the
    output is the same for any value: module docstring).
    """
    height = int(sensor_shape[0])
    margin = DEMOSAIC_REACH_PX[demosaic_method] + INTERPOLATION_REACH_PX[interpolation] + 4
    gap = 2 * INTERPOLATION_REACH_PX[interpolation]
    hexagonal = to_rect and grid.kind == "hexagonal"
    total = rect_row_count(grid.rows) if hexagonal else grid.rows
    step = max(1, rows_per_band or band_rows(m_hat, grid.cols, channels))

    def bands_of(out_rows: range) -> list:
        rows = hex_rows_read(out_rows, grid.rows) if hexagonal else out_rows
        y0, y1 = _strip(grid, m_hat, rows, margin, height, shift, rim is not None)
        # one remap reads the strip (or its four class strips stacked): rows below MAP_ROWS (and OpenCV's limit)
        read = y1 - y0 + 2 * gap + 1 if cells is None else CLASSES * (y1 - y0 + 2 * gap + 1)
        if read >= min(MAP_ROWS, CV_MAX_SIZE) and len(out_rows) > 1:
            half = out_rows.start + len(out_rows) // 2
            return bands_of(range(out_rows.start, half)) + bands_of(range(half, out_rows.stop))
        return [Band(rows, out_rows, y0, y1)]

    bands = []
    for r0 in range(0, total, step):
        bands += bands_of(range(r0, min(r0 + step, total)))
    return ReadPlan(grid, m_hat, cfa, demosaic_method, interpolation, (height, int(sensor_shape[1])), channels,
                    tuple(bands), tuple(view_runs(delivered, m_hat)), shift, cells, shares, rim)


def view_runs(delivered, m_hat: int | None = None) -> list[tuple[int, int, int]] | None:
    """``(ky, kx0, kx1)`` per view row with delivered views: the run from its first to its last one.

    Only these views are resampled and devignetted when a capture is decoded; the others are 0 and never
    computed (for a round aperture the runs hold about π/4 of the views of their bounding square).
    Without ``delivered``: every view row whole when ``m_hat`` is given, else None."""
    if delivered is None:
        return None if m_hat is None else [(ky, 0, m_hat) for ky in range(m_hat)]
    runs = []
    for ky, row in enumerate(np.asarray(delivered, dtype=bool)):
        kx = np.flatnonzero(row)
        if kx.size:
            runs.append((ky, int(kx[0]), int(kx[-1]) + 1))
    return runs
