"""Views on a hexagonal lens lattice resampled onto a rectangular one of the same pitch.

Hexagonal lens (r, q) sits at ((q + (r mod 2)/2)·p, r·(√3/2)·p) along (u, v). Rectangular lens (R, Q)
is taken at ((Q + ½)·p, R·p): half-way between the lenses of even rows and exactly on the lenses of
odd rows, so no column needs extrapolation. Each view is interpolated linearly along the two enclosing
hexagonal rows and then linearly between them. Row 0 of the hexagonal grid must be an unshifted row.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LfprocError
from ..grid import LensGrid

#: hexagonal rows per rectangular row (rectangular rows are one pitch apart, hexagonal ones √3/2)
HEX_ROWS_PER_RECT_ROW = 2.0 / math.sqrt(3.0)


def rect_row_count(hex_rows: int) -> int:
    """Rectangular rows that fit between the first and the last hexagonal row."""
    return int(math.floor((hex_rows - 1) / HEX_ROWS_PER_RECT_ROW + 1e-9)) + 1


def _upper_hex_row(big_r: int, hex_rows: int) -> int:
    return min(int(math.floor(big_r * HEX_ROWS_PER_RECT_ROW + 1e-9)), hex_rows - 2)


def hex_rows_read(rect_rows: range, hex_rows: int) -> range:
    """The hexagonal rows that rectangular ``rect_rows`` read, starting at an even (unshifted) row."""
    first = _upper_hex_row(rect_rows.start, hex_rows) & ~1
    return range(first, _upper_hex_row(rect_rows.stop - 1, hex_rows) + 2)


def hex_rows_to_rect(views: np.ndarray, first_hex_row: int, rect_rows: range, out: np.ndarray) -> None:
    """Write rectangular rows ``rect_rows`` into ``out[:, :, i]`` (i from 0) from hexagonal rows held in
    ``views[:, :, j]`` = hexagonal row ``first_hex_row + j`` (global row parity decides the shift)."""
    hex_rows_total = first_hex_row + views.shape[2]
    cols = views.shape[3]
    # two small reused scratch rows: on large light fields the cost is dominated by first touches of
    # freshly allocated memory, not by arithmetic
    upper = np.empty(views.shape[:2] + (cols - 1, views.shape[4]), dtype=np.float32)
    lower = np.empty_like(upper)

    def row_on_columns(r, dst):
        """Hexagonal row r read at the rectangular columns (Q + ½)·p."""
        row = views[:, :, r - first_hex_row]
        if r % 2 == 0:   # lenses at q·p: half-way between lenses Q and Q + 1
            np.add(row[:, :, :-1], row[:, :, 1:], out=dst)
            dst *= np.float32(0.5)
        else:            # lenses at (q + ½)·p: exactly on lens Q
            dst[...] = row[:, :, :-1]

    for i, big_r in enumerate(rect_rows):
        r0 = min(int(math.floor(big_r * HEX_ROWS_PER_RECT_ROW + 1e-9)), hex_rows_total - 2)
        t = np.float32(big_r * HEX_ROWS_PER_RECT_ROW - r0)
        row_on_columns(r0, upper)
        row_on_columns(r0 + 1, lower)
        np.multiply(upper, 1 - t, out=out[:, :, i])
        lower *= t
        out[:, :, i] += lower


def rect_grid_of(grid: LensGrid) -> LensGrid:
    """The rectangular grid of the lens positions :func:`hex_to_rect` resamples a hexagonal ``grid`` to.

    Only the rigid lattice changes (origin half a pitch along u, rows one pitch apart); other fields,
    such as a smooth deviation that is a function of the rigid position, are kept.
    """
    import dataclasses

    u, _ = grid.axes
    origin = np.asarray(grid.origin_xy_px) + 0.5 * grid.pitch_px * u
    return dataclasses.replace(grid, kind="rectangular", origin_xy_px=(float(origin[0]), float(origin[1])),
                               rows=rect_row_count(grid.rows), cols=grid.cols - 1)


def check_hex_size(rows: int, cols: int) -> None:
    if rows < 2 or cols < 2:
        raise LfprocError("a hexagonal light field needs at least 2 lens rows and columns to resample")


def hex_to_rect(views: np.ndarray, grid: LensGrid) -> tuple[np.ndarray, LensGrid]:
    """Resample views decoded on a hexagonal lens lattice onto a rectangular one of the same pitch.

    See the module docstring for the positions. A rectangular ``grid`` returns its input unchanged.

    Returns
    -------
    views : ndarray ``(m̂, m̂, R, cols − 1, C)``
    grid : LensGrid
        The rectangular grid of the resampled lens positions on the sensor.
    """
    if grid.kind != "hexagonal":
        return views, grid
    rows, cols = views.shape[2], views.shape[3]
    check_hex_size(rows, cols)
    n_rect_rows = rect_row_count(rows)
    out = np.empty(views.shape[:2] + (n_rect_rows, cols - 1, views.shape[4]), dtype=np.float32)
    hex_rows_to_rect(views, 0, range(n_rect_rows), out)
    return out, rect_grid_of(dataclass_replace_rows(grid, rows, cols))


def dataclass_replace_rows(grid: LensGrid, rows: int, cols: int) -> LensGrid:
    """``grid`` with ``rows`` × ``cols`` lenses (the views' own extent)."""
    import dataclasses

    return grid if (grid.rows, grid.cols) == (rows, cols) else dataclasses.replace(grid, rows=rows, cols=cols)
