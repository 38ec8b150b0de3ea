"""The `LensGrid` of a fitted lattice: which lenses it lists and how they are numbered.

The grid lists the lattice positions whose cell lies on the sensor (each centre at least half a pitch
inside it), as the smallest rows × cols index rectangle holding them all; then, in a rotated lattice, the
rectangle's edge rows and columns holding centres *off* the sensor are trimmed, so no listed lens has
its centre off the sensor.
"""

from __future__ import annotations

import math

import numpy as np

from ..grid import ROW_SPACING, LensGrid
from ._lattice import LatticeModel, Similarity, lattice_index, unit_coordinates


def lattice_indices_on_sensor(kind: str, model: LatticeModel, shape) -> np.ndarray:
    """Every lattice index (i, j) (as floats, (N, 2)) whose centre lies at least half a pitch inside the sensor."""
    h, w = shape
    corners = np.array([[-0.5, -0.5], [w - 0.5, -0.5], [-0.5, h - 0.5], [w - 0.5, h - 0.5]])
    ij = lattice_index(kind, model.st(corners))
    lo, hi = ij.min(0) - 3, ij.max(0) + 3  # i and j are linear in x, y: extreme at the corners
    ii, jj = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1))
    index = np.stack([ii.ravel(), jj.ravel()], -1).astype(np.float64)
    xy = model.xy(unit_coordinates(kind, index))
    margin = 0.5 * model.rigid.pitch
    inside = ((xy[:, 0] >= margin - 0.5) & (xy[:, 0] <= w - 0.5 - margin)
              & (xy[:, 1] >= margin - 0.5) & (xy[:, 1] <= h - 0.5 - margin))
    return index[inside]


def grid_from_fit(kind: str, model, index: np.ndarray, shape, rms: float) -> LensGrid:
    """The `LensGrid` (lfproc/grid.py convention) of the lenses ``index`` whose cell is on the sensor.

    ``model`` is a `Similarity` or a `LatticeModel`. In unit-lattice coordinates grid row R lies at
    t = (row0 + R)·row_spacing and its lens Q at s = s0 + Q + (R mod 2)/2 (hexagonal) or s = s0 + Q
    (rectangular). Every hexagonal row j has its s values at j/2 modulo 1, so any lattice point of row
    ``row0`` as origin satisfies the half-pitch convention; ``row0`` and ``s0`` are chosen so the lenses
    have R, Q ≥ 0 starting at 0. Edge rows and columns with centres off the sensor are then trimmed
    (module docstring); where no lens has its cell on the sensor, all of ``index`` is kept, untrimmed.
    """
    if isinstance(model, Similarity):
        model = LatticeModel(model)
    h, w = shape
    xy = model.xy(unit_coordinates(kind, index))
    margin = 0.5 * model.rigid.pitch
    on_sensor = ((xy[:, 0] >= margin - 0.5) & (xy[:, 0] <= w - 0.5 - margin)
                 & (xy[:, 1] >= margin - 0.5) & (xy[:, 1] <= h - 0.5 - margin))
    if not on_sensor.any():
        return _rectangle(kind, model, index, rms)[0]
    index = index[on_sensor]
    for _ in range(64):  # each round drops one edge row or column
        grid, rows_from_top, q = _rectangle(kind, model, index, rms)
        last_row, last_col = grid.rows - 1, grid.cols - 1
        cols, rows = np.arange(grid.cols), np.arange(grid.rows)
        edges = []
        for row, col, mask in ((0, cols, rows_from_top == 0), (last_row, cols, rows_from_top == last_row),
                               (rows, 0, q == 0), (rows, last_col, q == last_col)):
            xy = grid.lens_xy(row, col)  # only the edges: inner lenses lie between them
            off = (xy[:, 0] < -0.5) | (xy[:, 0] > w - 0.5) | (xy[:, 1] < -0.5) | (xy[:, 1] > h - 0.5)
            edges.append((int(off.sum()), mask))
        if max(e[0] for e in edges) == 0 or grid.rows < 2 or grid.cols < 2:
            return grid
        index = index[~max(edges, key=lambda e: e[0])[1]]
    return grid


def _rectangle(kind: str, model: LatticeModel, index: np.ndarray, rms: float):
    """The smallest grid rectangle holding ``index``, and each index's grid row and column."""
    st = unit_coordinates(kind, index)
    row0 = float(index[:, 1].min())
    rows_from_top = index[:, 1] - row0
    s_row0 = 0.5 * row0 if kind == "hexagonal" else 0.0  # s of lattice index (0, row0)
    q = st[:, 0] - s_row0
    if kind == "hexagonal":
        q = q - 0.5 * np.mod(rows_from_top, 2.0)
    q = np.rint(q)
    q0 = float(q.min())
    rigid = model.rigid
    origin = rigid.xy(np.array([s_row0 + q0, row0 * ROW_SPACING[kind]]))
    grid = LensGrid(kind=kind, pitch_px=rigid.pitch, rotation_deg=math.degrees(rigid.rotation_rad),
                    origin_xy_px=(float(origin[0]), float(origin[1])), rows=int(rows_from_top.max()) + 1,
                    cols=int(q.max() - q0) + 1, residual_rms_px=rms, deviation=model.deviation)
    return grid, rows_from_top, q - q0
