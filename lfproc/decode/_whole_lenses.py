"""Partial lenses: the lens grid cropped to the lenses whose every delivered sample lies on the sensor.

A lens near the sensor border whose micro image is cut by the border would decode its missing part as
0 (outside the sensor) or, after the division by the white image, as an extrapolation of what is left:
black or wrong samples in views and slices. The decoder therefore keeps only the largest block of lens
rows and columns whose delivered views (see ``_view_mask``) sample pixel centres inside the sensor
(``0 ≤ x ≤ W − 1``, ``0 ≤ y ≤ H − 1``). The cropped grid is an ordinary grid of those lenses, so lens
index j of the decoded views is lens j of ``LightField.grid``: refocusing and depth keep the contract's
indexing. A hexagonal crop starts on an even (unshifted) row, as the lattice convention requires.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import LfprocError
from ..grid import LensGrid
from ._positions import lens_centers, view_offsets_px


def whole_lens_mask(grid: LensGrid, m_hat: int, views: np.ndarray, sensor_shape, shift=None) -> np.ndarray:
    """Boolean ``(rows, cols)``: lenses whose samples of the ``views`` (an ``(m̂, m̂)`` mask) are on the sensor."""
    height, width = sensor_shape[:2]
    off_x, off_y = view_offsets_px(grid, m_hat, shift)
    if not views.any():
        views = np.zeros_like(views)
        views[(m_hat - 1) // 2, (m_hat - 1) // 2] = True
    ox, oy = off_x[views], off_y[views]
    centers = lens_centers(grid)
    x, y = centers[..., 0], centers[..., 1]
    eps = 1e-6
    return ((x + ox.min() >= -eps) & (x + ox.max() <= width - 1 + eps)
            & (y + oy.min() >= -eps) & (y + oy.max() <= height - 1 + eps))


def largest_whole_block(whole: np.ndarray, even_start_row: bool) -> tuple[int, int, int, int]:
    """``(r0, q0, rows, cols)`` of a block of lenses, all whole, found by trimming the border row or
    column with the largest share of partial lenses until none is left (rows start even when asked)."""
    r0, r1, q0, q1 = 0, whole.shape[0], 0, whole.shape[1]
    while r1 > r0 and q1 > q0:
        block = whole[r0:r1, q0:q1]
        if even_start_row and r0 % 2:
            r0 += 1
            continue
        if block.all():
            return r0, q0, r1 - r0, q1 - q0
        bad = {"top": (~block[0]).mean(), "bottom": (~block[-1]).mean(),
               "left": (~block[:, 0]).mean(), "right": (~block[:, -1]).mean()}
        side = max(bad, key=bad.get)
        if side == "top":
            r0 += 2 if even_start_row else 1
        elif side == "bottom":
            r1 -= 1
        elif side == "left":
            q0 += 1
        else:
            q1 -= 1
    raise LfprocError("no micro lens lies wholly on the sensor; check the grid (`lfproc.calibrate_white`) and the "
                      "camera's pitch")


def sub_grid(grid: LensGrid, r0: int, q0: int, rows: int, cols: int) -> LensGrid:
    """The lenses ``[r0, r0 + rows) × [q0, q0 + cols)`` of ``grid`` as a grid of their own.

    The new origin is the *rigid* lattice position of lens (r0, q0) (``r0`` even on hexagonal grids),
    and every other field is kept: a deviation that is a function of the rigid position (a smooth,
    non-rigid fit) then gives the same centres as before.
    """
    if (r0, q0, rows, cols) == (0, 0, grid.rows, grid.cols):
        return grid
    if grid.kind == "hexagonal" and r0 % 2:
        raise LfprocError("a hexagonal grid can only be cut at an even row")
    u, v = grid.axes
    origin = np.asarray(grid.origin_xy_px) + q0 * grid.pitch_px * u + r0 * grid.row_spacing_px * v
    return dataclasses.replace(grid, origin_xy_px=(float(origin[0]), float(origin[1])), rows=rows, cols=cols)


def crop_to_whole_lenses(grid: LensGrid, m_hat: int, views: np.ndarray, sensor_shape, shift=None) -> LensGrid:
    """``grid`` cropped to its largest block of whole lenses (see the module docstring); ``shift`` moves
    the views' samples off nominal (:func:`view_offsets_px`)."""
    whole = whole_lens_mask(grid, m_hat, views, sensor_shape, shift)
    r0, q0, rows, cols = largest_whole_block(whole, even_start_row=grid.kind == "hexagonal")
    return sub_grid(grid, r0, q0, rows, cols)
