"""Step 5 of calibration: index the measured centres and fit the lattice (rigid, or rigid plus smooth).

Nearest neighbours give the kind (4 → rectangular, 6 → hexagonal), pitch and rotation; lattice indices
are assigned from the middle outwards while the fit is refined, and the similarity lattice
``x = O + p·R(θ)·(s, t)`` — linear in (O, p cos θ, p sin θ) — is fitted by least squares with iterative
rejection of outliers. Where the lattice drifts (a non-rigid lattice), the growth predicts the next
lenses from a rigid lattice plus a smooth polynomial deviation (`_smooth_fit`), so a slowly changing
pitch never misnumbers distant lenses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..grid import SmoothDeviation

_SQRT3_2 = math.sqrt(3.0) / 2.0


@dataclass(frozen=True)
class Similarity:
    """The lattice ``x = origin + s·(a, b) + t·(−b, a)`` in unit-lattice coordinates (s, t).

    ``a = p·cos θ`` and ``b = p·sin θ``; a lens of index (i, j) has (s, t) from `unit_coordinates`.
    """

    origin: np.ndarray
    a: float
    b: float

    @property
    def pitch(self) -> float:
        return math.hypot(self.a, self.b)

    @property
    def rotation_rad(self) -> float:
        return math.atan2(self.b, self.a)

    def xy(self, st: np.ndarray) -> np.ndarray:
        """Sensor positions (…, 2) of unit-lattice coordinates (…, 2)."""
        s, t = st[..., 0], st[..., 1]
        return np.stack([self.origin[0] + self.a * s - self.b * t, self.origin[1] + self.b * s + self.a * t], -1)

    def st(self, xy: np.ndarray) -> np.ndarray:
        """Fractional unit-lattice coordinates of sensor positions (the inverse of :meth:`xy`)."""
        dx, dy = xy[..., 0] - self.origin[0], xy[..., 1] - self.origin[1]
        scale = self.a * self.a + self.b * self.b
        return np.stack([(self.a * dx + self.b * dy) / scale, (-self.b * dx + self.a * dy) / scale], -1)


@dataclass(frozen=True)
class LatticeModel:
    """A rigid `Similarity` plus an optional smooth deviation D: centre = p + D(p), p = rigid position."""

    rigid: Similarity
    deviation: SmoothDeviation | None = None

    def xy(self, st: np.ndarray) -> np.ndarray:
        p = self.rigid.xy(st)
        return p if self.deviation is None else p + self.deviation.offsets_at(p)

    def st(self, xy: np.ndarray) -> np.ndarray:
        """Fractional unit-lattice coordinates: the rigid inverse, corrected by fixed-point iteration."""
        st = self.rigid.st(xy)
        if self.deviation is not None:
            for _ in range(4):  # D is small and smooth: p = x − D(p) converges in a few steps
                st = self.rigid.st(xy - self.deviation.offsets_at(self.rigid.xy(st)))
        return st


def neighbour_lattice(xy: np.ndarray) -> tuple[str, float, float, int] | None:
    """Kind, pitch, rotation (radians, axis nearest +x) and support from nearest-neighbour vectors.

    Neighbours within ±20 % of the median nearest distance count; a lens with 5 or 6 of them is in a
    hexagonal lattice, with 4 in a rectangular one (diagonals lie at √2 pitch). The rotation is the
    circular mean of the neighbour directions folded by the lattice's symmetry (×4 or ×6). ``support``
    is the number of lenses with 3 or more such neighbours; ``None`` when fewer than 3 have.
    """
    from scipy.spatial import cKDTree
    if len(xy) < 4:
        return None
    dist, idx = cKDTree(xy).query(xy, k=min(7, len(xy)))
    dist, idx = dist[:, 1:], idx[:, 1:]
    nearest = float(np.median(dist[:, 0]))
    band = (dist > 0.8 * nearest) & (dist < 1.2 * nearest)
    counts = band.sum(1)
    well = counts >= 3
    if well.sum() < 3:
        return None
    kind = "hexagonal" if float(np.median(counts[well])) >= 5 else "rectangular"
    sel = band & well[:, None]
    vec = xy[idx] - xy[:, None, :]
    fold = 6 if kind == "hexagonal" else 4
    angle = np.arctan2(vec[..., 1][sel], vec[..., 0][sel])
    rotation = float(np.angle(np.exp(1j * fold * angle).sum())) / fold
    return kind, float(np.median(dist[sel])), rotation, int(well.sum())


def unit_coordinates(kind: str, index: np.ndarray) -> np.ndarray:
    """Unit-lattice coordinates (s, t) of lattice indices (i, j): rectangular (i, j), hexagonal (i + j/2, j·√3/2)."""
    i, j = index[..., 0].astype(np.float64), index[..., 1].astype(np.float64)
    if kind == "hexagonal":
        return np.stack([i + 0.5 * j, _SQRT3_2 * j], -1)
    return np.stack([i, j], -1)


def lattice_index(kind: str, st: np.ndarray) -> np.ndarray:
    """Nearest lattice indices (i, j) (as floats) of fractional unit-lattice coordinates (s, t)."""
    if kind == "hexagonal":
        j = np.rint(st[..., 1] / _SQRT3_2)
        return np.stack([np.rint(st[..., 0] - 0.5 * j), j], -1)
    return np.rint(st)


def fit_similarity(xy: np.ndarray, st: np.ndarray) -> Similarity:
    """Least squares ``x = O + s·(a, b) + t·(−b, a)``: linear in the 4 unknowns (Ox, Oy, a, b)."""
    n = len(xy)
    design = np.zeros((2 * n, 4))
    design[0::2, 0] = 1.0
    design[1::2, 1] = 1.0
    design[0::2, 2], design[0::2, 3] = st[:, 0], -st[:, 1]
    design[1::2, 2], design[1::2, 3] = st[:, 1], st[:, 0]
    sol = np.linalg.lstsq(design, xy.reshape(-1), rcond=None)[0]
    return Similarity(np.array(sol[:2]), float(sol[2]), float(sol[3]))


def robust_fit(xy: np.ndarray, st: np.ndarray, usable: np.ndarray, reject_sigma: float = 4.0,
               floor_px: float = 0.01, max_rounds: int = 20) -> tuple[Similarity, np.ndarray]:
    """Fit, drop centres beyond ``reject_sigma`` robust deviations, refit until the inlier set settles.

    The per-axis deviation comes from the median residual distance (a Rayleigh median is 1.1774 σ); the
    limit is at least ``floor_px`` and at most a quarter pitch.
    """
    inlier = usable.copy()
    model = fit_similarity(xy[inlier], st[inlier])
    for _ in range(max_rounds):
        residual = np.hypot(*(xy - model.xy(st)).T)
        sigma = float(np.median(residual[inlier])) / 1.1774
        limit = min(max(reject_sigma * sigma, floor_px), 0.25 * model.pitch)
        new = usable & (residual <= limit)
        if new.sum() < 3 or np.array_equal(new, inlier):
            break
        inlier = new
        model = fit_similarity(xy[inlier], st[inlier])
    return model, inlier


