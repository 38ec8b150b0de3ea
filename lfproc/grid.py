"""The micro lens lattice on the sensor: the one description shared by calibration, decoding and the simulator.

Coordinates are in sensor pixels, x = column and y = row, with the centre of pixel (0, 0) at (0, 0).
A lattice has two unit axes: ``u`` at ``rotation_deg`` from +x towards +y, and ``v`` = ``u`` turned
by +90°. Lens (r, q) — row r, column q — sits at

* rectangular: ``origin + q·pitch·u + r·pitch·v``
* hexagonal:   ``origin + (q + (r mod 2)/2)·pitch·u + r·(√3/2)·pitch·v`` (odd rows shifted by half a pitch)

A non-rigid lattice (a micro lens array that is not perfectly regular, or distorted optics) adds a smooth
`SmoothDeviation` to these rigid positions: lens centre = rigid position p + D(p), where D is a
polynomial in the sensor position p (so it does not depend on how the lenses are numbered).

A grid fitted to a white image (`lfproc.calibrate_white`) carries its `Calibration`: what it was fitted
from and what the fit measured. `LensGrid.save` writes the grid file (GRID.json, what ``lfproc
calibrate`` writes) and `LensGrid.load` reads one back, with its calibration and the file it came from.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from dataclasses import dataclass, field

import numpy as np

from .errors import LfprocError

#: how a message tells a Python caller to make a grid file (the commands word it as their command)
MAKE_GRID = "lfproc.calibrate_white(white, camera).save(path)"

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


@dataclass(frozen=True, repr=False)
class Calibration:
    """What a lens grid was fitted from and what the fit measured: the keys of a grid file beside the lattice
    (written by `LensGrid.save` in this order; docs/calibration.md, docs/inputs.md).

    Attributes
    ----------
    white_image : str or None
        The white image's file (absolute path); None for one given as an array.
    camera : str or None
        The camera file (absolute path); None for a camera built in Python.
    texture_ratio : float or None
        How much the micro images differ from their neighbours (`lfproc.calibrate.white_texture`).
    micro_image_scale, micro_image_scale_sigma : float or None
        The fitted micro image pitch over the camera's lens pitch, ``(d_A + f_s)/d_A``, and its standard error.
    implied_exit_pupil_distance_mm : float or None
        The exit pupil distance d_A that scale implies, mm (``inf``: telecentric within the fit).
    implied_exit_pupil_range_mm : tuple of float or None
        d_A for the scale within its allowance, mm (an end ``inf`` where it reaches telecentric).
    pitch_sigma_px : float or None
        Standard error of the fitted pitch, px.
    made_from : dict or None
        ``{"camera": {...}, "white": {...}, "dark": {...} or None}`` (`lfproc.inputs.made_from`); None in
        grid files written before it was recorded.
    measured_centers_xy_px, inlier : ndarray, shapes (N, 2) and (N,), or None
        Every micro image centre the fit measured (x, y; px) and those it used: in memory only, after a fit.
    """

    white_image: str | None = None
    camera: str | None = None
    texture_ratio: float | None = None
    micro_image_scale: float | None = None
    micro_image_scale_sigma: float | None = None
    implied_exit_pupil_distance_mm: float | None = None
    implied_exit_pupil_range_mm: tuple | None = None
    pitch_sigma_px: float | None = None
    made_from: dict | None = None
    measured_centers_xy_px: np.ndarray | None = field(default=None, compare=False)
    inlier: np.ndarray | None = field(default=None, compare=False)

    #: the keys a grid file holds beside the lattice, in the order written
    KEYS = ("white_image", "camera", "texture_ratio", "micro_image_scale", "micro_image_scale_sigma",
            "implied_exit_pupil_distance_mm", "implied_exit_pupil_range_mm", "pitch_sigma_px", "made_from")

    @property
    def camera_facts(self) -> dict | None:
        """The camera's numbers the grid was fitted for (``made_from["camera"]``), or None."""
        return (self.made_from or {}).get("camera") or None

    @property
    def white_facts(self) -> dict | None:
        """The white image's size, Bayer pattern, path and hash (``made_from["white"]``), or None."""
        return (self.made_from or {}).get("white") or None

    @property
    def dark_facts(self) -> dict | None:
        """The dark frame's path, hash and size (``made_from["dark"]``), or None."""
        return (self.made_from or {}).get("dark") or None

    def to_json_dict(self) -> dict:
        """The grid file's keys beside the lattice (``inf`` as ``null``, see `LensGrid.save`)."""
        return {key: getattr(self, key) for key in self.KEYS}

    @classmethod
    def from_json_dict(cls, data: dict, lattice_pitch_px: float, source: str) -> Calibration:
        """The calibration recorded in a grid file's ``data`` (any version; a damaged ``made_from`` is refused)."""
        made_from = data.get("made_from")
        if made_from is not None and not _valid_made_from(made_from):
            raise LfprocError(f"{source}: its 'made_from' record is damaged; fit the grid again with {MAKE_GRID}")
        span = data.get("implied_exit_pupil_range_mm")
        white, camera = data.get("white_image"), data.get("camera")
        return cls(white_image=white if isinstance(white, str) else None,
                   camera=camera if isinstance(camera, str) else None,
                   texture_ratio=_number(data, "texture_ratio"), micro_image_scale=_number(data, "micro_image_scale"),
                   micro_image_scale_sigma=_number(data, "micro_image_scale_sigma"),
                   implied_exit_pupil_distance_mm=_number(data, "implied_exit_pupil_distance_mm"),
                   implied_exit_pupil_range_mm=(tuple(_number({"end": v}, "end") for v in span)
                                                if isinstance(span, list) and len(span) == 2 else None),
                   pitch_sigma_px=_pitch_sigma(data, lattice_pitch_px), made_from=made_from)

    def __repr__(self) -> str:
        return (f"Calibration(white_image={self.white_image!r}, pitch_sigma_px={self.pitch_sigma_px}, "
                f"texture_ratio={self.texture_ratio}, made_from={'recorded' if self.made_from else None})")


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
            raise LfprocError(f"{source}: {exc}; fit the grid again with {MAKE_GRID}") from None

    def save(self, path) -> None:
        """Write the grid file ``path`` (GRID.json, atomically): the lattice, its centres and the calibration,
        exactly what ``lfproc calibrate -o`` writes for the same inputs.

        Strict JSON (infinity as ``null``), one top-level key per line: the json module's C encoder writes the
        230,000 ``centers_xy_px`` of a 41 Mpx sensor at once, where an indented dump takes seconds.
        """
        from .atomic import json_safe, write_text_atomic

        record = dict(self.to_json_dict(), **({} if self.calibration is None else self.calibration.to_json_dict()))
        items = []
        for key, value in record.items():
            safe = value if key == "centers_xy_px" else json_safe(value)  # centres: finite floats already
            items.append(f"  {json.dumps(str(key))}: {json.dumps(safe, allow_nan=False)}")
        write_text_atomic(path, "{\n" + ",\n".join(items) + "\n}\n")

    @classmethod
    def load(cls, path) -> LensGrid:
        """A grid file written by :meth:`save` or ``lfproc calibrate`` (any version), with its calibration and
        ``source`` (the path); one-line errors naming the file."""
        path = os.fspath(path)
        try:
            with open(path, encoding="utf-8") as fh:
                data = json.load(fh)
        except FileNotFoundError:
            raise LfprocError(f"{path}: grid file not found; check the path, or make one with {MAKE_GRID}") from None
        except IsADirectoryError:
            raise LfprocError(f"{path}: is a folder, not a grid file; pass the grid file saved by "
                              f"{MAKE_GRID}") from None
        except (OSError, ValueError) as exc:
            reason = getattr(exc, "strerror", None) or str(exc)
            raise LfprocError(f"{path}: not a readable grid file ({reason}); fit the grid again with "
                              f"{MAKE_GRID}") from None
        if not isinstance(data, dict):
            raise LfprocError(f"{path}: not a grid file; fit the grid again with {MAKE_GRID}")
        lattice = cls.from_json_dict(data, source=path)
        calibration = Calibration.from_json_dict(data, lattice.pitch_px, path)
        return dataclasses.replace(lattice, calibration=calibration, source=path)

    def __repr__(self) -> str:
        made = "" if self.calibration is None else f", fitted to {self.calibration.white_image or 'an array'}"
        return (f"LensGrid({self.kind}, {self.rows} x {self.cols} lenses, pitch {self.pitch_px:.4f} px, rotation "
                f"{self.rotation_deg:.4f} deg, {self.model}{made})")


def _number(data: dict, key: str) -> float | None:
    """``data[key]`` as a float: ``null`` is infinity (as `save` writes it), a missing key or a non-number None."""
    value = data.get(key, False)
    if value is None:
        return math.inf
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _valid_made_from(made_from) -> bool:
    """Whether a ``made_from`` record has the types the checks rely on (a damaged file is refused, not trusted)."""
    if not isinstance(made_from, dict):
        return False
    camera, white, dark = made_from.get("camera"), made_from.get("white"), made_from.get("dark")
    if not isinstance(camera, dict) or not all(_positive(camera.get(k)) for k in ("lens_pitch_px", "micro_image_scale")):
        return False
    if not all(_optional(camera.get(k), str) for k in ("grid", "cfa")):
        return False
    if white is not None and not (isinstance(white, dict) and all(_count(white.get(k)) for k in ("width", "height"))
                                  and _optional(white.get("channels"), int) and all(
                                      _optional(white.get(k), str) for k in ("cfa", "path", "hash"))):
        return False
    return dark is None or (isinstance(dark, dict) and all(_optional(dark.get(k), str) for k in ("path", "hash")))


def _positive(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0


def _count(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value > 0


def _optional(value, kind) -> bool:
    return value is None or (isinstance(value, kind) and not isinstance(value, bool))


def _pitch_sigma(data: dict, pitch_px: float) -> float | None:
    """``pitch_sigma_px`` where recorded; else from ``micro_image_scale_sigma`` (grid files of version 1)."""
    value = data.get("pitch_sigma_px")
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0:
        return float(value)
    scale, sigma = data.get("micro_image_scale"), data.get("micro_image_scale_sigma")
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (scale, sigma)) \
            and scale > 0 and sigma >= 0:
        return float(sigma) / float(scale) * pitch_px
    return None
