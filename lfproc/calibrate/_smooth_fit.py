"""Non-rigid lattices: a rigid similarity plus a smooth polynomial deviation, fitted robustly.

Real micro lens arrays and main lenses distort: PlenoptiCam's synthetic white image *d* has a pitch that
drifts from 7.4 to 8.0 px across the sensor. The lens centres are then modelled as ``p + D(p)``, p the
best rigid lattice position and D a 2-D Legendre series (`lfproc.grid.SmoothDeviation`) in the
normalised sensor position. The rigid part and D together are a polynomial of the lattice
coordinates, so fitting the similarity first and D to its residuals is the joint least-squares fit.
Each candidate (rigid = degree 0, or degree 2 … `MAX_DEGREE`) is scored by its 5-fold cross-validated
RMS over its inliers (the error of predicting centres it was not fitted to), so a polynomial that
follows the noise of few lenses scores worse than the rigid lattice; the lowest degree within 5 % of the
best score wins.
"""

from __future__ import annotations

import numpy as np

from ..grid import SmoothDeviation
from ._lattice import LatticeModel, fit_similarity

#: highest total degree of the deviation polynomial
MAX_DEGREE = 7
#: lowest degree tried when a smooth lattice is fitted
MIN_DEGREE = 2


def _terms(degree: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(degree + 1) for j in range(degree + 1) if i + j <= degree]


def _design(xy: np.ndarray, degree: int, center, half) -> np.ndarray:
    from numpy.polynomial import legendre
    xn = (xy[:, 0] - center[0]) / half[0]
    yn = (xy[:, 1] - center[1]) / half[1]
    vx, vy = legendre.legvander(xn, degree), legendre.legvander(yn, degree)
    return np.stack([vx[:, i] * vy[:, j] for i, j in _terms(degree)], -1)


def fit_deviation(positions: np.ndarray, offsets: np.ndarray, degree: int, center, half) -> SmoothDeviation:
    """Least-squares `SmoothDeviation` of total ``degree`` with D(positions) ≈ offsets (both (N, 2))."""
    design = _design(positions, degree, center, half)
    sol = np.linalg.lstsq(design, offsets, rcond=None)[0]  # (terms, 2)
    cx = np.zeros((degree + 1, degree + 1))
    cy = np.zeros_like(cx)
    for (i, j), (vx, vy) in zip(_terms(degree), sol):
        cx[i, j], cy[i, j] = vx, vy
    return SmoothDeviation(degree, tuple(center), tuple(half), tuple(cx.ravel()), tuple(cy.ravel()))


def robust_smooth_fit(xy: np.ndarray, st: np.ndarray, usable: np.ndarray, degree: int, center, half,
                      reject_sigma: float = 4.0, floor_px: float = 0.01,
                      max_rounds: int = 10) -> tuple[LatticeModel, np.ndarray]:
    """Rigid plus degree-``degree`` deviation, refitted without centres beyond ``reject_sigma`` deviations.

    As :func:`lfproc.calibrate._lattice.robust_fit`, with the smooth model in place of the similarity.
    """
    inlier = usable.copy()
    model = None
    for _ in range(max_rounds):
        rigid = fit_similarity(xy[inlier], st[inlier])
        p = rigid.xy(st)
        deviation = fit_deviation(p[inlier], (xy - p)[inlier], degree, center, half) if degree > 0 else None
        model = LatticeModel(rigid, deviation)
        residual = np.hypot(*(xy - model.xy(st)).T)
        sigma = float(np.median(residual[inlier])) / 1.1774
        limit = min(max(reject_sigma * sigma, floor_px), 0.25 * rigid.pitch)
        new = usable & (residual <= limit)
        if new.sum() < 2 * len(_terms(degree)) + 4 or np.array_equal(new, inlier):
            break
        inlier = new
    return model, inlier


def rms(model: LatticeModel, xy: np.ndarray, st: np.ndarray, inlier: np.ndarray) -> float:
    """RMS distance of the ``inlier`` centres from the model."""
    return float(np.sqrt(np.mean(np.sum((xy[inlier] - model.xy(st[inlier])) ** 2, axis=1))))


def cross_validated_rms(xy: np.ndarray, st: np.ndarray, inlier: np.ndarray, degree: int, center, half,
                        folds: int = 5) -> float:
    """RMS of each inlier's distance from the model fitted (plainly) to the other folds' inliers."""
    idx = np.flatnonzero(inlier)
    fold = np.random.default_rng(0).permutation(len(idx)) % folds
    squared = np.empty(len(idx))
    for k in range(folds):
        train, test = idx[fold != k], idx[fold == k]
        rigid = fit_similarity(xy[train], st[train])
        p = rigid.xy(st[train])
        deviation = fit_deviation(p, xy[train] - p, degree, center, half) if degree > 0 else None
        model = LatticeModel(rigid, deviation)
        squared[fold == k] = np.sum((xy[test] - model.xy(st[test])) ** 2, axis=1)
    return float(np.sqrt(np.mean(squared)))


def best_smooth_fit(xy: np.ndarray, st: np.ndarray, usable: np.ndarray, center, half,
                    rigid_score: float) -> tuple[LatticeModel, np.ndarray, float, float] | None:
    """The best-scoring smooth fit (module docstring), or ``None`` when none beats ``rigid_score`` by 20 %.

    Degrees run from `MIN_DEGREE` to `MAX_DEGREE`, as far as 10 centres per coefficient allow.
    Returns the model, its inliers, their RMS and its cross-validated score.
    """
    fits = []
    for degree in range(MIN_DEGREE, MAX_DEGREE + 1):
        if usable.sum() < 10 * len(_terms(degree)):
            break
        model, inlier = robust_smooth_fit(xy, st, usable, degree, center, half)
        score = cross_validated_rms(xy, st, inlier, degree, center, half)
        fits.append((model, inlier, rms(model, xy, st, inlier), score))
    fits = [f for f in fits if f[3] < 0.8 * rigid_score]
    if not fits:
        return None
    best = min(f[3] for f in fits)
    return next(f for f in fits if f[3] <= 1.05 * best)
