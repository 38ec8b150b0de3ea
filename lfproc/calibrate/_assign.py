"""Lattice indices for measured centres, grown from the middle outwards with the fit refined on the way.

Within a radius of 3 lenses, then 1.6 times as far at each round, each centre takes the index of the
nearest lattice point of the current fit (if within 0.3 pitch of it), and the fit is redone; so a small
error of the first pitch or rotation never misnumbers distant lenses. Where the rigid lattice leaves
residuals above 2 % of the pitch (a drifting pitch) the prediction is the rigid lattice plus a smooth
polynomial deviation of degree 2 (3 beyond 30 lenses), which follows a smoothly changing pitch.
"""

from __future__ import annotations

import math

import numpy as np

from ._lattice import LatticeModel, Similarity, lattice_index, robust_fit, unit_coordinates
from ._smooth_fit import rms, robust_smooth_fit

#: the indexed radius grows by this factor each round
GROWTH = 1.6
#: a centre farther than this fraction of the pitch from the predicted lattice point gets no index
CAPTURE = 0.3


class NoLattice(Exception):
    """Too few centres line up with any lattice."""


def assign_and_fit(xy: np.ndarray, usable: np.ndarray, kind: str, pitch: float, rotation: float,
                   center, half) -> tuple[LatticeModel, np.ndarray, np.ndarray, np.ndarray]:
    """Index the centres, growing the indexed region outwards from the lens nearest the middle.

    ``center`` and ``half`` normalise sensor positions for a smooth deviation (`_smooth_fit`).
    Returns the last prediction model, the indices (N, 2), their unit-lattice coordinates and the mask
    of usable centres within `CAPTURE` of their lattice point.
    """
    middle = np.median(xy[usable], axis=0)
    candidates = np.flatnonzero(usable)
    ref = candidates[np.argmin(np.hypot(*(xy[candidates] - middle).T))]
    model = LatticeModel(Similarity(xy[ref].copy(), pitch * math.cos(rotation), pitch * math.sin(rotation)))
    radius = 3.0
    while True:
        index, st, close = _index(kind, model, xy, pitch)
        near = np.max(np.abs(index), axis=1) <= radius
        sel = usable & close & near
        if sel.sum() < 3:
            raise NoLattice
        model = _prediction_model(xy, st, sel, radius, center, half)
        if np.all(np.max(np.abs(index[usable & close]), axis=1) <= radius):
            index, st, close = _index(kind, model, xy, pitch)
            return model, index, st, usable & close
        radius *= GROWTH


def _index(kind: str, model: LatticeModel, xy: np.ndarray, pitch: float):
    index = lattice_index(kind, model.st(xy))
    st = unit_coordinates(kind, index)
    close = np.hypot(*(xy - model.xy(st)).T) < CAPTURE * pitch
    return index, st, close


def _prediction_model(xy, st, sel, radius, center, half) -> LatticeModel:
    """The rigid fit, or where it leaves residuals above 2 % of the pitch, rigid plus a smooth deviation."""
    rigid, _ = robust_fit(xy, st, sel)
    model = LatticeModel(rigid)
    drifting = rms(model, xy, st, sel) > 0.02 * rigid.pitch
    if drifting and radius >= 9.0 and sel.sum() >= 40:
        model, _ = robust_smooth_fit(xy, st, sel, 2 if radius < 30.0 else 3, center, half)
    return model
