"""Devignetting: the white image's views, inverted where they carry signal (the decoder's ``inverse_white``)."""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError
from ._band import read_band, sensor_levels
from ._plan import ReadPlan
from ._view_mask import central_range

#: samples of the white image's views used for its bright level (a strided subset beyond this)
LEVEL_SAMPLES = 4_000_000
#: a sample read from its own cell needs at least this share of its kernel on the cell's pixels
MIN_OWN_WEIGHT = 0.05


def inverse_white(white: np.ndarray, plan: ReadPlan, dark_fraction: float,
                  delivered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(inverse, signal)``: 1 / white views where the white carries signal in every channel and the view is
    delivered, else 0; and the share of each view's samples that carry signal over the central 60 % of the
    lenses (:func:`._view_mask.carrying_views`). ``plan`` reads ``white`` (every view, the grid's own rows).

    Reading own cells (``plan.cells``), a sample's white is compared with the threshold per unit of its
    kernel's weight on its own cell: a view read near the micro image's edge puts little weight on the
    lit pixels but stands for them alone (the weight cancels in capture / white). With cell shares
    (rim-aware decoding) a sample below the threshold is not set to 0 but divided by the threshold: it
    fades out as its white does, so that a grid a hundredth of a pixel off does not switch it on or off.
    """
    grid, m_hat, cells, shares = plan.grid, plan.m_hat, plan.cells, plan.shares
    inverse = np.empty((m_hat, m_hat, grid.rows, grid.cols, plan.channels), dtype=np.float32)
    levels = sensor_levels(plan, white)
    for band in plan.bands:
        inverse[:, :, band.rows.start:band.rows.stop] = read_band(plan, band, white, levels=levels)
    flat = inverse.reshape(-1)
    subset = flat[::max(1, flat.size // LEVEL_SAMPLES)]
    bright = float(np.percentile(subset, 99)) if subset.size else 0.0
    if not bright > 0:
        raise LfprocError("the white image is black at every lens centre; check the white image and the grid")
    threshold = np.float32(dark_fraction * bright)
    ones = None if cells is None else np.broadcast_to(np.float32(1.0), white.shape)   # no full-size copy
    counted = np.zeros((m_hat, m_hat))
    (r0, r1), (q0, q1) = central_range(grid.rows), central_range(grid.cols)
    for band in plan.bands:
        rows = band.rows
        views = inverse[:, :, rows.start:rows.stop]
        weight = None if cells is None else read_band(plan, band, ones)
        for ky in range(m_hat):      # per view row: the boolean temporaries stay small
            w = views[ky]
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
