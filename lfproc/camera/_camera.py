"""The camera: optical parameters of a Standard Plenoptic Camera, their validation and TOML loading.

All lengths are in millimetres. The file format is the contract of ``ARCHITECTURE.md``::

    [sensor]     pixel_pitch_mm, cfa, black_level, white_level
    [mla]        pitch_mm, focal_length_mm, principal_plane_gap_mm, grid
    [main_lens]  focal_length_mm, principal_plane_gap_mm,
                 image_distance_mm | focus_distance_mm, f_number
    [decode]     micro_image_px
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace

from .errors import LfprocError
from .tomlfile import parse_toml, read_toml


GRIDS = ("rectangular", "hexagonal")
CFA_PATTERNS = ("none", "RGGB", "BGGR", "GRBG", "GBRG")
_ODD_TOLERANCE = 1e-6
#: dataclass field -> the key a user writes in the camera file (for error messages)
#: every key a camera file may hold, per table (anything else is a typo and refused)
KNOWN_KEYS = {
    "": {"name", "sensor", "mla", "main_lens", "decode"},
    "sensor": {"pixel_pitch_mm", "cfa", "black_level", "white_level"},
    "mla": {"pitch_mm", "focal_length_mm", "principal_plane_gap_mm", "grid"},
    "main_lens": {"focal_length_mm", "principal_plane_gap_mm", "image_distance_mm", "focus_distance_mm", "f_number",
                  "exit_pupil_distance_mm"},
    "decode": {"micro_image_px"},
}
TOML_KEYS = {
    "pixel_pitch_mm": "sensor.pixel_pitch_mm", "black_level": "sensor.black_level",
    "white_level": "sensor.white_level", "mla_pitch_mm": "mla.pitch_mm",
    "mla_focal_length_mm": "mla.focal_length_mm", "mla_principal_plane_gap_mm": "mla.principal_plane_gap_mm",
    "main_focal_length_mm": "main_lens.focal_length_mm",
    "main_principal_plane_gap_mm": "main_lens.principal_plane_gap_mm",
    "image_distance_mm": "main_lens.image_distance_mm", "f_number": "main_lens.f_number",
    "exit_pupil_distance_mm": "main_lens.exit_pupil_distance_mm",
}


def largest_odd_at_most(ratio: float) -> int:
    """Largest odd integer not above ``ratio``; a ratio within 1e-6 of an odd integer counts as it.

    This is the contract's default micro image size m̂ for ``pitch_mm / pixel_pitch_mm``.
    """
    nearest = round(ratio)
    if nearest % 2 == 1 and abs(ratio - nearest) <= _ODD_TOLERANCE * max(1.0, ratio):
        return int(nearest)
    m = int(math.floor(ratio))
    if m % 2 == 0:
        m -= 1
    return max(m, 1)


@dataclass(frozen=True)
class Camera:
    """Optical parameters of a Standard Plenoptic Camera (the paper's Table 1 and Section 5.1).

    Parameters
    ----------
    pixel_pitch_mm : float
        Physical sensor pixel pitch p_p.
    mla_pitch_mm : float
        Micro lens pitch p_m̂.
    mla_focal_length_mm : float
        Micro lens focal length f_s; the sensor sits f_s behind the MLA.
    main_focal_length_mm : float
        Main lens focal length f_U.
    image_distance_mm : float
        b_U, main lens (H2U) to MLA (H1s). Must be at least f_U.
    mla_principal_plane_gap_mm, main_principal_plane_gap_mm : float
        Separations H1s–H2s and H1U–H2U (negative where the planes are interchanged).
    f_number : float or None
        Main lens f-number, for the Airy limit (Eq. 22) and aperture checks.
    grid : {"rectangular", "hexagonal"}
    cfa : {"none", "RGGB", "BGGR", "GRBG", "GBRG"}
    black_level : float
        Raw black level for TIFF/PNG captures (0 by default).
    white_level : float or None
        Raw white level for TIFF/PNG captures; ``None`` (the default) takes the file's own maximum
        (255 for 8-bit files, 65535 for 16-bit ones; camera raws always carry their own levels).
    exit_pupil_distance_mm : float
        d_A, the distance from the micro lens array to the main lens's exit pupil, towards the object.
        ``inf`` (the default) is the image-side telecentric case of the 2014 paper; a finite value
        shifts micro image centres outwards from their lenses (Hahne et al. 2018, PlenoptiSign's dA).
    micro_image_px : int or None
        Odd micro image size m̂ after resampling; ``None`` picks the largest odd integer not above
        ``mla_pitch_mm / pixel_pitch_mm``. Always an ``int`` once constructed.
    name : str
        Optional label.
    """

    pixel_pitch_mm: float
    mla_pitch_mm: float
    mla_focal_length_mm: float
    main_focal_length_mm: float
    image_distance_mm: float
    mla_principal_plane_gap_mm: float = 0.0
    main_principal_plane_gap_mm: float = 0.0
    f_number: float | None = None
    grid: str = "rectangular"
    cfa: str = "none"
    black_level: float = 0.0
    white_level: float | None = None
    exit_pupil_distance_mm: float = math.inf
    micro_image_px: int | None = None
    name: str = ""
    source: str = field(default="", compare=False, repr=False)

    def __post_init__(self):
        where = self.source or "camera"
        for key in ("pixel_pitch_mm", "mla_pitch_mm", "mla_focal_length_mm", "main_focal_length_mm"):
            _require_positive(getattr(self, key), key, where)
        for key in ("image_distance_mm", "mla_principal_plane_gap_mm", "main_principal_plane_gap_mm",
                    "black_level"):
            _require_finite(getattr(self, key), key, where)
        if self.white_level is not None:
            _require_finite(self.white_level, "white_level", where)
        d_a = self.exit_pupil_distance_mm
        if isinstance(d_a, bool) or not isinstance(d_a, (int, float)) or math.isnan(d_a) or d_a <= 0:
            raise LfprocError(f"{where}: main_lens.exit_pupil_distance_mm must be a positive distance or inf, "
                              f"got {d_a!r}")
        if self.f_number is not None:
            _require_positive(self.f_number, "f_number", where)
        if self.image_distance_mm < self.main_focal_length_mm:
            raise LfprocError(
                f"{where}: main_lens.image_distance_mm = {self.image_distance_mm} is below the main lens focal length "
                f"{self.main_focal_length_mm}, so the main lens would focus beyond infinity; "
                f"set image_distance_mm >= focal_length_mm (or give focus_distance_mm)")
        if self.grid not in GRIDS:
            raise LfprocError(f"{where}: unknown mla.grid {self.grid!r}; use one of {', '.join(GRIDS)}")
        if self.cfa not in CFA_PATTERNS:
            raise LfprocError(f"{where}: unknown sensor.cfa {self.cfa!r}; use one of {', '.join(CFA_PATTERNS)}")
        if self.white_level is not None and self.white_level <= self.black_level:
            raise LfprocError(f"{where}: white_level {self.white_level} must exceed black_level {self.black_level}")
        ratio = self.mla_pitch_mm / self.pixel_pitch_mm
        if self.micro_image_px is None:
            if ratio < 1.0 - _ODD_TOLERANCE:
                raise LfprocError(f"{where}: the micro lens pitch {self.mla_pitch_mm} mm is smaller than one pixel "
                                  f"({self.pixel_pitch_mm} mm); check the units of both pitches")
            object.__setattr__(self, "micro_image_px", largest_odd_at_most(ratio))
        else:
            m = self.micro_image_px
            if isinstance(m, bool) or not isinstance(m, int) or m < 1 or m % 2 == 0:
                raise LfprocError(f"{where}: decode.micro_image_px must be an odd integer >= 1, got {m!r}; "
                                  f"try {largest_odd_at_most(max(ratio, 1.0))}")

    # ----------------------------------------------------------------- derived quantities
    @property
    def m_hat(self) -> int:
        """Micro image size m̂ in pixels after resampling (odd)."""
        return int(self.micro_image_px)

    @property
    def center_index(self) -> int:
        """c = (m̂ − 1) / 2, the index of the central view."""
        return (self.m_hat - 1) // 2

    @property
    def effective_pixel_pitch_mm(self) -> float:
        """Pixel pitch the geometry sees after resampling: ``mla_pitch_mm / m̂``."""
        return self.mla_pitch_mm / self.m_hat

    @property
    def sensor_to_main_lens_mm(self) -> float:
        """f_s + H1sH2s + b_U + H1UH2U: the constant path of Eqs. 21 and 31 (sensor to H1U)."""
        return (self.mla_focal_length_mm + self.mla_principal_plane_gap_mm + self.image_distance_mm
                + self.main_principal_plane_gap_mm)

    @property
    def telecentric(self) -> bool:
        """True when the exit pupil is at infinity (the 2014 paper's model)."""
        return math.isinf(self.exit_pupil_distance_mm)

    def raw_levels(self, type_max: float) -> tuple[float, float]:
        """(black, white) for a file whose integer type saturates at ``type_max``.

        The white level given in the camera file wins; without one, the file's own maximum.
        """
        white = float(type_max) if self.white_level is None else float(self.white_level)
        return float(self.black_level), white

    @property
    def pitch_px(self) -> float:
        """Micro lens pitch in physical sensor pixels (before resampling)."""
        return self.mla_pitch_mm / self.pixel_pitch_mm

    def with_focus_distance(self, focus_distance_mm: float) -> "Camera":
        """A copy whose b_U focuses the main lens at ``focus_distance_mm`` (from the sensor)."""
        return replace(self, image_distance_mm=image_distance_for_focus(
            self.main_focal_length_mm, focus_distance_mm,
            self.mla_focal_length_mm + self.mla_principal_plane_gap_mm + self.main_principal_plane_gap_mm,
            self.source or "camera"))

    # ----------------------------------------------------------------- files
    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> "Camera":
        """Load a camera file (contract format); every problem raises `LfprocError` naming the file."""
        path = os.fspath(path)
        data = read_toml(path, "camera file", "an existing TOML file to --camera")
        return cls.from_dict(data, source=path)

    @classmethod
    def from_toml_string(cls, text: str, source: str = "camera") -> "Camera":
        data = parse_toml(text, source, "camera file")
        return cls.from_dict(data, source=source)

    @classmethod
    def from_dict(cls, data: dict, source: str = "camera") -> "Camera":
        """Build a camera from the parsed TOML tables (see the module docstring)."""
        reader = _TableReader(data, source)
        sensor, mla, main, decode = (reader.table(t, required=t != "decode") for t in
                                     ("sensor", "mla", "main_lens", "decode"))
        for table, known in KNOWN_KEYS.items():
            given = data if not table else data.get(table, {})
            unknown = sorted(set(given) - known) if isinstance(given, dict) else []
            if unknown:
                where = f"[{table}]" if table else "the top level"
                raise LfprocError(f"{source}: unknown key {unknown[0]!r} in {where}; the keys there are "
                                  f"{', '.join(sorted(known))}")
        f_u = reader.number(main, "main_lens", "focal_length_mm")
        main_gap = reader.number(main, "main_lens", "principal_plane_gap_mm", default=0.0)
        f_s = reader.number(mla, "mla", "focal_length_mm")
        mla_gap = reader.number(mla, "mla", "principal_plane_gap_mm", default=0.0)
        has_b, has_focus = "image_distance_mm" in main, "focus_distance_mm" in main
        if has_b and has_focus:
            raise LfprocError(f"{source}: [main_lens] gives both image_distance_mm and focus_distance_mm; keep one")
        if not (has_b or has_focus):
            raise LfprocError(f"{source}: [main_lens] needs image_distance_mm or focus_distance_mm; add one")
        if has_b:
            b_u = reader.number(main, "main_lens", "image_distance_mm")
        else:
            focus = reader.number(main, "main_lens", "focus_distance_mm", allow_inf=True)
            _require_positive(f_u, "main_lens.focal_length_mm", source)
            b_u = image_distance_for_focus(f_u, focus, f_s + mla_gap + main_gap, source)
        micro = decode.get("micro_image_px") if decode else None
        if micro is not None and (isinstance(micro, bool) or not isinstance(micro, int)):
            if isinstance(micro, float) and micro.is_integer():
                micro = int(micro)
            else:
                raise LfprocError(f"{source}: decode.micro_image_px must be an odd integer, got {micro!r}")
        exit_pupil = reader.number(main, "main_lens", "exit_pupil_distance_mm", default=math.inf, allow_inf=True)
        f_number = main.get("f_number")
        if f_number is not None:
            f_number = reader.number(main, "main_lens", "f_number")
        name = data.get("name", "")
        if not isinstance(name, str):
            raise LfprocError(f"{source}: name must be a string, got {name!r}")
        return cls(
            pixel_pitch_mm=reader.number(sensor, "sensor", "pixel_pitch_mm"),
            mla_pitch_mm=reader.number(mla, "mla", "pitch_mm"),
            mla_focal_length_mm=f_s,
            main_focal_length_mm=f_u,
            image_distance_mm=b_u,
            mla_principal_plane_gap_mm=mla_gap,
            main_principal_plane_gap_mm=main_gap,
            f_number=f_number,
            grid=reader.string(mla, "mla", "grid", "rectangular"),
            cfa=reader.string(sensor, "sensor", "cfa", "none"),
            black_level=reader.number(sensor, "sensor", "black_level", default=0.0),
            white_level=(reader.number(sensor, "sensor", "white_level") if "white_level" in sensor else None),
            exit_pupil_distance_mm=exit_pupil,
            micro_image_px=micro,
            name=name,
            source=source,
        )

    def to_toml(self) -> str:
        """The camera as a contract TOML file (b_U written as ``image_distance_mm``; full precision)."""
        lines = []
        if self.name:
            lines.append(f"name = {_toml_str(self.name)}")
        lines += ["[sensor]", f"pixel_pitch_mm = {self.pixel_pitch_mm!r}", f"cfa = {_toml_str(self.cfa)}",
                  f"black_level = {float(self.black_level)!r}"]
        if self.white_level is not None:
            lines.append(f"white_level = {float(self.white_level)!r}")
        lines += ["[mla]", f"pitch_mm = {self.mla_pitch_mm!r}", f"focal_length_mm = {self.mla_focal_length_mm!r}",
                  f"principal_plane_gap_mm = {self.mla_principal_plane_gap_mm!r}", f"grid = {_toml_str(self.grid)}",
                  "[main_lens]", f"focal_length_mm = {self.main_focal_length_mm!r}",
                  f"principal_plane_gap_mm = {self.main_principal_plane_gap_mm!r}",
                  f"image_distance_mm = {self.image_distance_mm!r}"]
        if self.f_number is not None:
            lines.append(f"f_number = {self.f_number!r}")
        if not self.telecentric:
            lines.append(f"exit_pupil_distance_mm = {self.exit_pupil_distance_mm!r}")
        lines += ["[decode]", f"micro_image_px = {self.m_hat}"]
        return "\n".join(lines) + "\n"


def image_distance_for_focus(focal_length_mm: float, focus_distance_mm: float, fixed_path_mm: float,
                             where: str = "camera") -> float:
    """b_U that focuses a thick main lens at ``focus_distance_mm`` measured from the sensor.

    The object distance from H1U is z = D − (f_s + H1sH2s + H1UH2U) − b_U, and the thin-lens
    equation 1/f_U = 1/b_U + 1/z holds between the principal planes. With K = b_U + z the root
    with z ≥ b_U is b_U = 2 f_U / (1 + sqrt(1 − 4 f_U / K)), written so that it is exact at K = ∞.

    Parameters
    ----------
    focal_length_mm : float
        f_U.
    focus_distance_mm : float
        Distance from the sensor to the focused object plane; ``inf`` gives b_U = f_U.
    fixed_path_mm : float
        f_s + H1sH2s + H1UH2U, the part of the sensor-to-object path that does not move.
    """
    if math.isnan(focus_distance_mm) or focus_distance_mm <= 0:
        raise LfprocError(f"{where}: main_lens.focus_distance_mm must be a positive distance or inf, "
                          f"got {focus_distance_mm}")
    if math.isinf(focus_distance_mm):
        return float(focal_length_mm)
    k = focus_distance_mm - fixed_path_mm
    if k < 4.0 * focal_length_mm:
        nearest = 4.0 * focal_length_mm + fixed_path_mm
        raise LfprocError(f"{where}: main_lens.focus_distance_mm = {focus_distance_mm} is closer than this lens can "
                          f"focus ({nearest:.3f} mm from the sensor); use a larger distance")
    return 2.0 * focal_length_mm / (1.0 + math.sqrt(1.0 - 4.0 * focal_length_mm / k))


class _TableReader:
    """Typed access to the parsed TOML with messages that name the file, table and key."""

    def __init__(self, data: dict, source: str):
        self.data, self.source = data, source

    def table(self, name: str, required: bool = True) -> dict:
        value = self.data.get(name)
        if value is None:
            if required:
                raise LfprocError(f"{self.source}: missing table [{name}]; see the camera file format in the README")
            return {}
        if not isinstance(value, dict):
            raise LfprocError(f"{self.source}: '{name}' must be a table [{name}], got {type(value).__name__}")
        return value

    def number(self, table: dict, tname: str, key: str, default=None, allow_inf: bool = False) -> float:
        if key not in table:
            if default is not None:
                return float(default)
            raise LfprocError(f"{self.source}: missing {tname}.{key}; add it to [{tname}] (millimetres)")
        value = table[key]
        if isinstance(value, str) and allow_inf and value.strip().lower() in ("inf", "infinity"):
            return math.inf
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise LfprocError(f"{self.source}: {tname}.{key} must be a number, got {value!r}")
        value = float(value)
        if math.isnan(value) or (math.isinf(value) and not allow_inf):
            raise LfprocError(f"{self.source}: {tname}.{key} must be finite, got {value}")
        return value

    def string(self, table: dict, tname: str, key: str, default: str) -> str:
        value = table.get(key, default)
        if not isinstance(value, str):
            raise LfprocError(f"{self.source}: {tname}.{key} must be a string, got {value!r}")
        return value


def _require_positive(value, key: str, where: str) -> None:
    key = TOML_KEYS.get(key, key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise LfprocError(f"{where}: {key} must be a finite positive number, got {value!r}")


def _require_finite(value, key: str, where: str) -> None:
    key = TOML_KEYS.get(key, key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise LfprocError(f"{where}: {key} must be a finite number, got {value!r}")


def _toml_str(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
