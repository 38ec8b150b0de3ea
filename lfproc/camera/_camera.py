"""The camera: optical parameters of a Standard Plenoptic Camera and the quantities derived from them.

All lengths are in millimetres. Validation lives in :mod:`._validation`, the camera file (TOML) in
:mod:`._toml`; this module holds only the frozen dataclass.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace

from ..errors import LfprocError
from ._lens import LensPrescription
from ._main_optics import MainLens, ObjectSpace
from ._microscope import Microscope
from ._optics import image_distance_for_focus
from ._validation import validate_camera


#: a main-lens argument not given (``None`` is a value: "no f-number")
_UNSET = object()
_LENS_DEFAULTS = {"focal_length_mm": None, "image_distance_mm": None, "principal_plane_gap_mm": 0.0,
                  "f_number": None, "exit_pupil_distance_mm": math.inf, "prescription": None}


@dataclass(frozen=True, init=False)
class Camera:
    """Optical parameters of a Standard Plenoptic Camera (the paper's Table 1 and Section 5.1).

    The sensor and the micro lens array are fields; everything in front of the MLA is one field,
    ``main_optics`` (a :class:`~._main_optics.MainLens` or a :class:`~._microscope.Microscope`, the one
    interface of :mod:`._main_optics`). The main lens can also be given by its camera-file values
    (``main_focal_length_mm=…``, as below), which build the :class:`MainLens`; read back, those names are
    properties of ``main_optics`` (``None`` for a microscope).

    Parameters
    ----------
    pixel_pitch_mm : float
        Physical sensor pixel pitch p_p.
    mla_pitch_mm : float
        Micro lens pitch p_m̂.
    mla_focal_length_mm : float
        Micro lens focal length f_s; the sensor sits f_s behind the MLA.
    main_focal_length_mm : float or None
        Main lens focal length f_U (``None`` only for a microscope).
    image_distance_mm : float or None
        b_U, main lens (H2U) to MLA (H1s). Must be at least f_U (``None`` only for a microscope).
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
        ``mla_pitch_mm / lenslet_pixel_pitch_mm`` (``pixel_pitch_mm`` unless a microscope has a relay). Always an ``int`` once constructed.
    main_lens_prescription : LensPrescription or None
        The main lens as its surfaces (``main_lens.prescription`` or ``[[main_lens.surfaces]]``); then
        f_U, H1U–H2U and d_A are its paraxial cardinal points (:mod:`._lens`), and real rays can be traced
        through it (``lfproc.geometry.real_ray_slices``). ``None``: the main lens is its cardinal points only.
    microscope : Microscope or None
        The objective, tube lens and relay of a light-field microscope (the ``[microscope]`` table),
        in place of a main lens; ``None`` for a photographic camera.
    main_optics : MainLens or Microscope, keyword only
        The main optics as one object, in place of the values above.
    name : str
        Optional label.
    source : str
        The file the camera came from (error messages only; not compared).
    provenance : tuple of (str, str)
        Where values came from, as (dotted camera-file key, short text) pairs, from the camera file's
        optional ``[provenance]`` table (e.g. written by ``lfproc camera`` from Lytro metadata).
    """

    pixel_pitch_mm: float
    mla_pitch_mm: float
    mla_focal_length_mm: float
    main_optics: MainLens | Microscope | None
    mla_principal_plane_gap_mm: float = 0.0
    grid: str = "rectangular"
    cfa: str = "none"
    black_level: float = 0.0
    white_level: float | None = None
    micro_image_px: int | None = None
    name: str = ""
    source: str = field(default="", compare=False, repr=False)
    provenance: tuple = field(default=(), compare=False, repr=False)

    def __init__(self, pixel_pitch_mm, mla_pitch_mm, mla_focal_length_mm, main_focal_length_mm=_UNSET,
                 image_distance_mm=_UNSET, mla_principal_plane_gap_mm=0.0, main_principal_plane_gap_mm=_UNSET,
                 f_number=_UNSET, grid="rectangular", cfa="none", black_level=0.0, white_level=None,
                 exit_pupil_distance_mm=_UNSET, micro_image_px=None, main_lens_prescription=_UNSET,
                 microscope=None, name="", source="", provenance=(), *, main_optics=None):
        lens_values = {key: value for key, value in (
            ("focal_length_mm", main_focal_length_mm), ("image_distance_mm", image_distance_mm),
            ("principal_plane_gap_mm", main_principal_plane_gap_mm), ("f_number", f_number),
            ("exit_pupil_distance_mm", exit_pupil_distance_mm), ("prescription", main_lens_prescription))
            if value is not _UNSET}
        where = source or "camera"
        if main_optics is not None and microscope is not None and microscope is not main_optics:
            raise LfprocError(f"{where}: give the main optics once (main_optics= or microscope=), not both")
        optics = main_optics if main_optics is not None else microscope
        if isinstance(optics, MainLens):
            optics = replace(optics, **lens_values)       # dataclasses.replace(camera, image_distance_mm=...)
        elif optics is not None:
            if any(value is not None and value != _LENS_DEFAULTS[key] for key, value in lens_values.items()):
                raise LfprocError(f"{where}: a microscope camera has no main lens; give [microscope] or "
                                  f"[main_lens], not both")
        elif lens_values.get("focal_length_mm") is not None and lens_values.get("image_distance_mm") is not None:
            optics = MainLens(**{key: _LENS_DEFAULTS[key] if value is None else value
                                 for key, value in lens_values.items() if key != "f_number"},
                              f_number=lens_values.get("f_number"))
        for key, value in (("pixel_pitch_mm", pixel_pitch_mm), ("mla_pitch_mm", mla_pitch_mm),
                           ("mla_focal_length_mm", mla_focal_length_mm), ("main_optics", optics),
                           ("mla_principal_plane_gap_mm", mla_principal_plane_gap_mm), ("grid", grid), ("cfa", cfa),
                           ("black_level", black_level), ("white_level", white_level),
                           ("micro_image_px", micro_image_px), ("name", name), ("source", source),
                           ("provenance", provenance)):
            object.__setattr__(self, key, value)
        # not a field (a replaced or rebuilt camera states its m̂): whether m̂ was left to the nominal pitch
        object.__setattr__(self, "_m_hat_from_pitch", self.micro_image_px is None)
        object.__setattr__(self, "micro_image_px", validate_camera(self))

    # ----------------------------------------------------------------- the main optics' values, by their file keys
    @property
    def main_lens(self) -> MainLens | None:
        """The photographic main lens (``[main_lens]``), or ``None`` for a microscope."""
        return self.main_optics if isinstance(self.main_optics, MainLens) else None

    @property
    def microscope(self) -> Microscope | None:
        """The objective, tube lens and relay (``[microscope]``), or ``None`` for a photographic camera."""
        return self.main_optics if isinstance(self.main_optics, Microscope) else None

    @property
    def main_focal_length_mm(self) -> float | None:
        """f_U (``None`` for a microscope)."""
        return None if self.main_lens is None else self.main_lens.focal_length_mm

    @property
    def image_distance_mm(self) -> float | None:
        """b_U, H2U to the MLA's H1s (``None`` for a microscope)."""
        return None if self.main_lens is None else self.main_lens.image_distance_mm

    @property
    def main_principal_plane_gap_mm(self) -> float:
        """H1U–H2U (0 for a microscope)."""
        return 0.0 if self.main_lens is None else self.main_lens.principal_plane_gap_mm

    @property
    def f_number(self) -> float | None:
        """The main lens f-number (``None`` where not given, and for a microscope: its aperture is its NA)."""
        return None if self.main_lens is None else self.main_lens.f_number

    @property
    def main_lens_prescription(self) -> LensPrescription | None:
        """The main lens's surfaces where the camera file gives them."""
        return None if self.main_lens is None else self.main_lens.prescription

    @property
    def exit_pupil_distance_mm(self) -> float:
        """d_A, the MLA to the main optics' exit pupil (``inf``: image-side telecentric)."""
        return math.inf if self.main_optics is None else self.main_optics.exit_pupil_distance_mm

    @property
    def object_space(self) -> ObjectSpace:
        """Unit and origin of every slice position and depth of this camera (:class:`~._main_optics.ObjectSpace`)."""
        return self.main_optics.object_space

    @property
    def micro_image_px_given(self) -> bool:
        """Whether m̂ was stated (``[decode] micro_image_px``, ``micro_image_px=``) rather than derived from the
        nominal pitch; a derived m̂ gives way to the measured micro image pitch (`lfproc.inputs.measured_m_hat`)."""
        return not getattr(self, "_m_hat_from_pitch", False)

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
    def telecentric(self) -> bool:
        """True when the exit pupil is at infinity (the 2014 paper's model; always for a microscope)."""
        return math.isinf(self.exit_pupil_distance_mm)

    def require_main_lens(self, what: str) -> None:
        """Raise `LfprocError` (one line) when ``what`` needs a main lens and this camera is a microscope."""
        if self.microscope is not None:
            raise LfprocError(f"{self.source or 'camera'}: {what} needs a main lens ([main_lens]); this camera "
                              f"file describes a microscope ([microscope]), which has none")

    @property
    def relay_magnification(self) -> float:
        """Lateral magnification from the lenslets' focal plane to the sensor (1 without a relay)."""
        return 1.0 if self.main_optics is None else float(self.main_optics.relay_magnification)

    @property
    def lenslet_pixel_pitch_mm(self) -> float:
        """The sensor pixel seen at the lenslets' focal plane: ``pixel_pitch_mm / relay_magnification``."""
        return self.pixel_pitch_mm / self.relay_magnification

    @property
    def micro_image_scale(self) -> float:
        """(d_A + f_s) / d_A: the micro image centre lattice is the lens lattice scaled by this about the axis.

        Exactly 1.0 for a telecentric camera (Hahne et al. 2018: the chief ray through a lens centre
        comes from the exit pupil centre, so it lands f_s·s/d_A further out than the lens at height s).
        """
        if self.telecentric:
            return 1.0
        return (self.exit_pupil_distance_mm + self.mla_focal_length_mm) / self.exit_pupil_distance_mm

    @property
    def micro_image_pitch_mm(self) -> float:
        """Pitch of the micro image centres on the sensor: ``mla_pitch_mm × micro_image_scale``."""
        return self.mla_pitch_mm * self.micro_image_scale

    @property
    def effective_pixel_pitch_mm(self) -> float:
        """The contract's effective pixel pitch ``mla_pitch_mm / m̂`` (the lens pitch over m̂)."""
        return self.mla_pitch_mm / self.m_hat

    @property
    def sample_pitch_mm(self) -> float:
        """Spacing of the decoded samples under each lens: the micro image pitch over m̂.

        The decoder resamples the calibrated micro image lattice (what a white image shows), one
        micro image pitch ``mla_pitch_mm × micro_image_scale`` to m̂ samples. The geometry uses this
        pitch; it is exactly :attr:`effective_pixel_pitch_mm` for a telecentric camera.
        """
        return self.micro_image_pitch_mm / self.m_hat

    @property
    def sensor_to_main_lens_mm(self) -> float:
        """f_s + H1sH2s + b_U + H1UH2U: the constant path of Eqs. 21 and 31 (sensor to H1U)."""
        self.require_main_lens("a distance from the sensor")
        return self.main_lens.sensor_path_mm(self.mla_path_mm)

    @property
    def mla_path_mm(self) -> float:
        """f_s + H1sH2s: the sensor to the MLA's H1s, the part of every path the main optics do not set."""
        return self.mla_focal_length_mm + self.mla_principal_plane_gap_mm

    @property
    def pitch_px(self) -> float:
        """Micro lens pitch in physical sensor pixels (before resampling; through the relay of a microscope)."""
        return self.mla_pitch_mm / self.lenslet_pixel_pitch_mm

    def raw_levels(self, type_max: float) -> tuple[float, float]:
        """(black, white) for a file whose integer type saturates at ``type_max``.

        The white level given in the camera file wins; without one, the file's own maximum.
        """
        white = float(type_max) if self.white_level is None else float(self.white_level)
        return float(self.black_level), white

    def provenance_of(self, key: str) -> str | None:
        """Where the value of a dotted camera-file key came from, if the camera file says."""
        return dict(self.provenance).get(key)

    def with_focus_distance(self, focus_distance_mm: float) -> "Camera":
        """A copy whose b_U focuses the main lens at ``focus_distance_mm`` (from the sensor).

        The provenance of b_U (or of a focus distance) no longer holds and is dropped.
        """
        self.require_main_lens("a focus distance")
        stale = ("main_lens.image_distance_mm", "main_lens.focus_distance_mm")
        b_u = image_distance_for_focus(
            self.main_focal_length_mm, focus_distance_mm,
            self.mla_focal_length_mm + self.mla_principal_plane_gap_mm + self.main_principal_plane_gap_mm,
            self.source or "camera")
        d_a = (self.exit_pupil_distance_mm if self.main_lens_prescription is None
               else self.main_lens_prescription.exit_pupil_distance_mm(b_u))
        return self._same_m_hat(replace(self, image_distance_mm=b_u, exit_pupil_distance_mm=d_a,
                                        provenance=tuple(p for p in self.provenance if p[0] not in stale)))

    def with_main_lens(self, prescription: LensPrescription, image_distance_mm: float | None = None) -> "Camera":
        """A copy whose main lens is ``prescription``: f_U, H1U–H2U and d_A become its cardinal points.

        ``image_distance_mm`` is b_U from the lens's rear principal plane (default: the camera's own).
        """
        self.require_main_lens("a main lens prescription")
        b_u = self.image_distance_mm if image_distance_mm is None else float(image_distance_mm)
        return self._same_m_hat(replace(self, main_focal_length_mm=prescription.focal_length_mm,
                                        main_principal_plane_gap_mm=prescription.principal_plane_gap_mm,
                                        image_distance_mm=b_u,
                                        exit_pupil_distance_mm=prescription.exit_pupil_distance_mm(b_u),
                                        main_lens_prescription=prescription))

    def _same_m_hat(self, copy: "Camera") -> "Camera":
        """``copy`` (this camera with another main lens focus or lens) leaving m̂ to the measurement as this one
        does: ``dataclasses.replace`` passes the derived m̂ on as if it were stated."""
        object.__setattr__(copy, "_m_hat_from_pitch", not self.micro_image_px_given)
        return copy

    # ----------------------------------------------------------------- files (see ._toml)
    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> "Camera":
        """Load a camera file (contract format); every problem raises `LfprocError` naming the file."""
        from ._toml import camera_fields, read_camera_file
        path = os.fspath(path)
        return cls(**camera_fields(read_camera_file(path), source=path))

    @classmethod
    def from_toml_string(cls, text: str, source: str = "camera") -> "Camera":
        """Load camera file text (e.g. stored inside a light field file)."""
        from ._toml import camera_fields, parse_camera_text
        return cls(**camera_fields(parse_camera_text(text, source), source=source))

    @classmethod
    def from_dict(cls, data: dict, source: str = "camera") -> "Camera":
        """Build a camera from the parsed TOML tables (see :mod:`lfproc.camera._toml`)."""
        from ._toml import camera_fields
        return cls(**camera_fields(data, source=source))

    def to_toml(self, include_provenance: bool = True) -> str:
        """The camera as a contract TOML file (b_U written as ``image_distance_mm``; full precision).

        ``include_provenance`` appends the ``[provenance]`` table (where the camera has one).
        """
        from ._toml import camera_to_toml
        return camera_to_toml(self, include_provenance)
