"""Where every view sample is read on the sensor, and the ``cv2.remap`` maps that read them.

View (ky, kx) of lens (r, q) is read at the lens centre plus ``(kx − c)·s·u + (ky − c)·s·v`` sensor
pixels, with s = pitch_px / m̂ the effective pixel (the geometry's ``pitch_mm / m̂``, Section 5.1) and
(u, v) the lattice axes. Lens centres always come from the grid itself (:meth:`LensGrid.lens_xy`),
so any lattice the grid describes, rigid or not, is sampled at its own centres. On a smooth (non-rigid)
lattice the micro images also grow, shrink and turn with the local lattice: there s·u is the local
step between half-lens positions, (lens_xy(r, q + ½) − lens_xy(r, q − ½))/m̂, and s·v that step turned by
90°, so the outer views of a lens with a drifting pitch stay on their own rays.
"""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError
from ..grid import LensGrid


def check_m_hat(m_hat: int) -> int:
    """``m_hat`` as an int, or LfprocError unless it is odd and at least 1."""
    if m_hat < 1 or m_hat % 2 == 0:
        raise LfprocError(f"micro image size must be odd and >= 1, got {m_hat}")
    return int(m_hat)


def view_offsets_px(grid: LensGrid, m_hat: int, shift=None) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (x, y) in sensor pixels of every view sample from its lens centre, each ``(m̂, m̂)``.

    View k sits (k − c)·pitch/m̂ from the centre along each lattice axis (contract: view index and
    lens index increase with the sensor coordinate). ``shift`` ``(m̂, m̂, 2)`` (sensor pixels x, y), when
    given, moves each view's samples off that nominal position: where the decoder reads a view so
    that its samples stand for their nominal rays (:mod:`lfproc.decode._view_mask`).
    """
    m_hat = check_m_hat(m_hat)
    c = (m_hat - 1) // 2
    k = (np.arange(m_hat) - c) * (grid.pitch_px / m_hat)
    u, v = grid.axes
    x, y = k[None, :] * u[0] + k[:, None] * v[0], k[None, :] * u[1] + k[:, None] * v[1]
    if shift is not None:
        x, y = x + shift[..., 0], y + shift[..., 1]
    return x, y


def lens_offsets_px(grid: LensGrid, m_hat: int, rows: range, shift=None) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (x, y) of every view sample from its lens centre for the lenses of ``rows``, each broadcastable
    to ``(m̂, m̂, len(rows), cols)``: the global ones (:func:`view_offsets_px`) on a rigid lattice, per lens
    from the local lattice on a smooth one (module docstring); plus ``shift`` (see :func:`view_offsets_px`)."""
    if grid.deviation is None:
        off_x, off_y = view_offsets_px(grid, m_hat, shift)
        return off_x[:, :, None, None], off_y[:, :, None, None]
    m_hat = check_m_hat(m_hat)
    r, q = np.meshgrid(np.arange(rows.start, rows.stop), np.arange(grid.cols), indexing="ij")
    step = (grid.lens_xy(r, q + 0.5) - grid.lens_xy(r, q - 0.5)) / m_hat    # s·u per lens, (R, C, 2)
    k = (np.arange(m_hat) - (m_hat - 1) // 2).astype(np.float64)
    kx, ky = k[None, :, None, None], k[:, None, None, None]
    x, y = kx * step[..., 0] - ky * step[..., 1], kx * step[..., 1] + ky * step[..., 0]
    if shift is not None:
        x, y = x + shift[:, :, 0, None, None], y + shift[:, :, 1, None, None]
    return x, y


def lens_centers(grid: LensGrid, rows: range | None = None) -> np.ndarray:
    """Centres (x, y) of the lenses of ``rows`` (default all), shape ``(len(rows), cols, 2)``, via ``grid.lens_xy``."""
    rows = range(grid.rows) if rows is None else rows
    r, q = np.meshgrid(np.arange(rows.start, rows.stop), np.arange(grid.cols), indexing="ij")
    return grid.lens_xy(r, q)


def sample_positions(grid: LensGrid, m_hat: int, shift=None) -> tuple[np.ndarray, np.ndarray]:
    """Sensor positions (x, y) of every view sample, each shaped ``(m̂, m̂, rows, cols)``, float64
    (``shift``: see :func:`view_offsets_px`)."""
    off_x, off_y = lens_offsets_px(grid, m_hat, range(grid.rows), shift)
    centers = lens_centers(grid)
    x = centers[None, None, :, :, 0] + off_x
    y = centers[None, None, :, :, 1] + off_y
    return x, y


def band_maps(grid: LensGrid, m_hat: int, rows: range, y0: int = 0,
              shift=None) -> list[tuple[np.ndarray, np.ndarray]]:
    """float32 remap maps of lens ``rows`` for every view row ky, each ``(m̂·len(rows), cols)``.

    Map rows run over (kx, r), so one ``remap`` per view row writes ``views[ky, :, rows]``. ``y0`` is
    subtracted from y: the maps read a sensor strip that starts at row ``y0``; ``shift``: see
    :func:`view_offsets_px`.
    """
    off_x, off_y = lens_offsets_px(grid, m_hat, rows, shift)
    centers = lens_centers(grid, rows).astype(np.float32)
    cx = centers[None, :, :, 0]
    cy = centers[None, :, :, 1] - np.float32(y0)
    shape = (m_hat * len(rows), grid.cols)
    return [((cx + off_x[ky].astype(np.float32)).reshape(shape),
             (cy + off_y[ky].astype(np.float32)).reshape(shape)) for ky in range(m_hat)]


def remap_maps(grid: LensGrid, m_hat: int, shift=None) -> list[tuple[np.ndarray, np.ndarray]]:
    """The float32 ``cv2.remap`` maps of every view row ky over all lenses, each ``(m̂·rows, cols)``."""
    return band_maps(grid, m_hat, range(grid.rows), shift=shift)


def sensor_rows_read(grid: LensGrid, m_hat: int, rows: range, margin: int, height: int,
                     shift=None) -> tuple[int, int]:
    """The sensor rows ``[y0, y1)`` that the samples of lens ``rows`` read, widened by ``margin`` and
    clipped to the sensor; ``y0`` is even so that a Bayer strip keeps the mosaic's phase."""
    _, off_y = lens_offsets_px(grid, m_hat, rows, shift)
    ys = lens_centers(grid, rows)[..., 1]
    lo = float(ys.min()) + float(off_y.min()) - margin
    hi = float(ys.max()) + float(off_y.max()) + margin
    y0 = max(0, int(np.floor(lo))) & ~1
    y1 = min(height, int(np.ceil(hi)) + 1)
    return y0, max(y1, y0)
