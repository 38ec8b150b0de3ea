"""The micro lens lattice on the sensor: the one description shared by calibration, decoding and the simulator.

Coordinates are in sensor pixels, x = column and y = row, with the centre of pixel (0, 0) at (0, 0).
A lattice has two unit axes: ``u`` at ``rotation_deg`` from +x towards +y, and ``v`` = ``u`` turned
by +90°. Lens (r, q) — row r, column q — sits at

* rectangular: ``origin + q·pitch·u + r·pitch·v``
* hexagonal:   ``origin + (q + (r mod 2)/2)·pitch·u + r·(√3/2)·pitch·v`` (odd rows shifted by half a pitch)

A non-rigid lattice (a micro lens array that is not perfectly regular, or distorted optics) adds a smooth
`SmoothDeviation` to these rigid positions: lens centre = rigid position p + D(p), where D is a
polynomial in the sensor position p (so it does not depend on how the lenses are numbered).

A grid fitted to a white image (`lfproc.calibrate_white`) carries its `lfproc.gridfile.Calibration`: what
it was fitted from and what the fit measured. `LensGrid.save` writes the grid file (GRID.json, what ``lfproc
calibrate`` writes) and `LensGrid.load` reads one back, with its calibration and the file it came from
(`lfproc.gridfile`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from .errors import LfprocError
from .gridfile import MAKE_GRID, Calibration

ROW_SPACING = {"rectangular": 1.0, "hexagonal": math.sqrt(3.0) / 2.0}


@dataclass(frozen=True)
class SmoothDeviation:
    """A smooth offset field D(x, y) of lens centres from the rigid lattice, in sensor pixels.

    D is a 2-D Legendre series of total degree ``degree`` in the normalised sensor position
    ``((x − cx)/hx, (y − cy)/hy)``; ``coeffs_x`` and ``coeffs_y`` hold its ``(degree + 1)²`` coefficients
    (row-major, index [i, j] multiplying P_i(x̂)·P_j(ŷ); those with i + j > degree are 0).

    Parameters
    ----------
    degree : int
    center_xy_px, half_size_px : tuple of float
        (cx, cy) and (hx, hy) of the normalisation (the sensor's centre and half size).
    coeffs_x, coeffs_y : tuple of float
    """

    degree: int
    center_xy_px: tuple
    half_size_px: tuple
    coeffs_x: tuple
    coeffs_y: tuple

    def __post_init__(self):
        n = (int(self.degree) + 1) ** 2
        values = [float(v) for v in (*self.center_xy_px, *self.half_size_px, *self.coeffs_x, *self.coeffs_y)]
        if (self.degree < 0 or len(self.coeffs_x) != n or len(self.coeffs_y) != n or len(self.center_xy_px) != 2
                or len(self.half_size_px) != 2 or not all(math.isfinite(v) for v in values)
                or min(self.half_size_px) <= 0):
            raise LfprocError(f"grid deviation: degree {self.degree} needs {n} finite coefficients per axis "
                              f"and a positive half size")
        for name in ("center_xy_px", "half_size_px", "coeffs_x", "coeffs_y"):
            object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))
        object.__setattr__(self, "degree", int(self.degree))

    def offsets_at(self, xy) -> np.ndarray:
        """D at sensor positions ``xy`` (..., 2): the offsets (dx, dy), shape (..., 2)."""
        from numpy.polynomial import legendre
        xy = np.asarray(xy, dtype=np.float64)
        xn = (xy[..., 0] - self.center_xy_px[0]) / self.half_size_px[0]
        yn = (xy[..., 1] - self.center_xy_px[1]) / self.half_size_px[1]
        shape = (self.degree + 1, self.degree + 1)
        cx = np.reshape(self.coeffs_x, shape)
        cy = np.reshape(self.coeffs_y, shape)
        return np.stack([legendre.legval2d(xn, yn, cx), legendre.legval2d(xn, yn, cy)], axis=-1)

    def to_json_dict(self) -> dict:
        return {"basis": "legendre", "degree": self.degree, "center_xy_px": list(self.center_xy_px),
                "half_size_px": list(self.half_size_px), "coeffs_x": list(self.coeffs_x),
                "coeffs_y": list(self.coeffs_y)}

    @classmethod
    def from_json_dict(cls, data: dict) -> SmoothDeviation:
        if data.get("basis", "legendre") != "legendre":
            raise LfprocError(f"unknown grid deviation basis {data.get('basis')!r}")
        return cls(degree=int(data["degree"]), center_xy_px=tuple(data["center_xy_px"]),
                   half_size_px=tuple(data["half_size_px"]), coeffs_x=tuple(data["coeffs_x"]),
                   coeffs_y=tuple(data["coeffs_y"]))

    def __repr__(self) -> str:
        return f"SmoothDeviation(degree {self.degree}, {len(self.coeffs_x) + len(self.coeffs_y)} coefficients)"


@dataclass(frozen=True)
class LensGrid:
    """A fitted or simulated micro lens lattice (see the module docstring for the convention).

    Parameters
    ----------
    kind : {"rectangular", "hexagonal"}
    pitch_px : float
        Distance between neighbouring lens centres along ``u``, in sensor pixels.
    rotation_deg : float
        Angle of ``u`` from +x towards +y (the lattice axis nearest to +x).
    origin_xy_px : tuple of float
        Centre of lens (0, 0).
    rows, cols : int
        Number of lens rows (along ``v``) and columns (along ``u``).
    residual_rms_px : float
        RMS distance between measured centres and the lattice, where fitted.
    deviation : SmoothDeviation or None
        Smooth offsets of the lens centres from the rigid lattice (a non-rigid lattice); ``None`` = rigid.
        ``pitch_px``, ``rotation_deg`` and ``origin_xy_px`` then describe the best rigid lattice.
    calibration : Calibration or None
        What the grid was fitted from (`lfproc.calibrate_white`, or a grid file's record); None for a
        lattice made otherwise. Not part of the lattice: grids compare equal without it.
    source : str or None
        The grid file it was read from (`load`), for messages and provenance; None otherwise.
    """

    kind: str
    pitch_px: float
    rotation_deg: float
    origin_xy_px: tuple
    rows: int
    cols: int
    residual_rms_px: float = 0.0
    deviation: SmoothDeviation | None = None
    calibration: Calibration | None = field(default=None, compare=False)
    source: str | None = field(default=None, compare=False)

    @property
    def model(self) -> str:
        """``"rigid"`` or ``"smooth"`` (a rigid lattice plus a `SmoothDeviation`)."""
        return "rigid" if self.deviation is None else "smooth"

    def __post_init__(self):
        if self.kind not in ROW_SPACING:
            raise LfprocError(f"unknown grid kind {self.kind!r}; use rectangular or hexagonal")
        if len(self.origin_xy_px) != 2:
            raise LfprocError(f"grid origin_xy_px must be two numbers (x, y), got {self.origin_xy_px!r}")
        origin = (float(self.origin_xy_px[0]), float(self.origin_xy_px[1]))
        if not (math.isfinite(self.pitch_px) and self.pitch_px > 0):
            raise LfprocError(f"grid pitch_px must be a finite positive number of pixels, got {self.pitch_px}")
        if not (math.isfinite(self.rotation_deg) and all(math.isfinite(v) for v in origin)):
            raise LfprocError("grid rotation_deg and origin_xy_px must be finite numbers")
        for name in ("rows", "cols"):
            value = getattr(self, name)
            if isinstance(value, bool) or not float(value).is_integer() or value < 1:
                raise LfprocError(f"grid {name} must be a whole number >= 1, got {value}")
            object.__setattr__(self, name, int(value))
        object.__setattr__(self, "origin_xy_px", origin)

    @property
    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors (u, v) in (x, y)."""
        t = math.radians(self.rotation_deg)
        return np.array([math.cos(t), math.sin(t)]), np.array([-math.sin(t), math.cos(t)])

    @property
    def row_spacing_px(self) -> float:
        """Distance between lens rows along ``v``."""
        return self.pitch_px * ROW_SPACING[self.kind]

    def lens_xy(self, row, col) -> np.ndarray:
        """Centres (x, y) of lenses at integer (or fractional) ``row``, ``col``; shape ``(..., 2)``.

        With a `deviation`, the rigid position p plus D(p).
        """
        row = np.asarray(row, dtype=np.float64)
        col = np.asarray(col, dtype=np.float64)
        u, v = self.axes
        shift = 0.5 * np.mod(np.floor(row), 2.0) if self.kind == "hexagonal" else 0.0
        along_u = (col + shift) * self.pitch_px
        along_v = row * self.row_spacing_px
        x = self.origin_xy_px[0] + along_u * u[0] + along_v * v[0]
        y = self.origin_xy_px[1] + along_u * u[1] + along_v * v[1]
        xy = np.stack([x, y], axis=-1)
        if self.deviation is not None:
            xy = xy + self.deviation.offsets_at(xy)
        return xy

    def centers_xy_px(self) -> np.ndarray:
        """All lens centres, shape ``(rows, cols, 2)`` as (x, y)."""
        r, q = np.meshgrid(np.arange(self.rows), np.arange(self.cols), indexing="ij")
        return self.lens_xy(r, q)

    def to_json_dict(self) -> dict:
        """The contract's GRID.json fields plus what is needed to rebuild the lattice."""
        return {
            "grid": self.kind,
            "pitch_px": self.pitch_px,
            "rotation_deg": self.rotation_deg,
            "residual_rms_px": self.residual_rms_px,
            "origin_xy_px": list(self.origin_xy_px),
            "rows": self.rows,
            "cols": self.cols,
            "row_spacing_px": self.row_spacing_px,
            "centers_xy_px": self.centers_xy_px().reshape(-1, 2).tolist(),
            "model": self.model,
            "deviation": None if self.deviation is None else self.deviation.to_json_dict(),
        }

    @classmethod
    def from_json_dict(cls, data: dict, source: str = "grid") -> LensGrid:
        """The lattice of :meth:`to_json_dict`'s ``data`` (its calibration is :meth:`load`'s)."""
        try:
            return cls(kind=str(data["grid"]), pitch_px=float(data["pitch_px"]),
                       rotation_deg=float(data["rotation_deg"]),
                       origin_xy_px=tuple(float(v) for v in data["origin_xy_px"]),
                       rows=float(data["rows"]), cols=float(data["cols"]),
                       residual_rms_px=float(data.get("residual_rms_px", 0.0)),
                       deviation=(None if data.get("deviation") is None
                                  else SmoothDeviation.from_json_dict(data["deviation"])))
        except (KeyError, TypeError, ValueError, OverflowError, AttributeError) as exc:
            raise LfprocError(f"{source}: not a lens grid ({exc!r}); fit the grid again with {MAKE_GRID}") from None
        except LfprocError as exc:
            raise LfprocError(f"{source}: {exc.marked}; fit the grid again with {MAKE_GRID}") from None

    def save(self, path) -> None:
        """Write the grid file ``path`` (GRID.json, atomically): the lattice, its centres and the calibration,
        exactly what ``lfproc calibrate -o`` writes for the same inputs (`lfproc.gridfile.write_grid_file`)."""
        from .gridfile import write_grid_file

        write_grid_file(path, dict(self.to_json_dict(),
                                   **({} if self.calibration is None else self.calibration.to_json_dict())))

    @classmethod
    def load(cls, path) -> LensGrid:
        """A grid file written by :meth:`save` or ``lfproc calibrate`` (any version), with its calibration and
        ``source`` (the path); one-line errors naming the file (`lfproc.gridfile.read_grid_file`)."""
        from .gridfile import read_grid_file

        data = read_grid_file(path)
        lattice = cls.from_json_dict(data, source=str(path))
        calibration = Calibration.from_json_dict(data, lattice.pitch_px, str(path))
        return dataclasses.replace(lattice, calibration=calibration, source=str(path))

    def __repr__(self) -> str:
        made = "" if self.calibration is None else f", fitted to {self.calibration.white_image or 'an array'}"
        return (f"LensGrid({self.kind}, {self.rows} x {self.cols} lenses, pitch {self.pitch_px:.4f} px, rotation "
                f"{self.rotation_deg:.4f} deg, {self.model}{made})")
