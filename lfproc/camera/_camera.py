"""The camera: optical parameters of a Standard Plenoptic Camera and the quantities derived from them.

All lengths are in millimetres. Validation lives in :mod:`._validation`, the camera file (TOML) in
:mod:`._toml`; this module holds only the frozen dataclass.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace

from ._main_optics import MainOptics
from ._optics import largest_odd_at_most
from ._validation import validate_camera


@dataclass(frozen=True)
class Camera:
    """Optical parameters of a Standard Plenoptic Camera (the paper's Table 1 and Section 5.1).

    The sensor and the micro lens array are fields; everything in front of the MLA is one field,
    ``main_optics``: a :class:`~._main_lens.MainLens`, a :class:`~._microscope.Microscope` or any other
    implementation of :class:`~._main_optics.MainOptics`. Its values are its own (``camera.main_optics``);
    a copy with other optics is :meth:`with_optics`.

    Parameters
    ----------
    pixel_pitch_mm : float
        Physical sensor pixel pitch p_p.
    mla_pitch_mm : float
        Micro lens pitch p_m̂.
    mla_focal_length_mm : float
        Micro lens focal length f_s; the sensor sits f_s behind the MLA.
    main_optics : MainOptics
        Everything in front of the micro lens array (the camera file's ``[main_lens]`` or ``[microscope]``).
    mla_principal_plane_gap_mm : float
        Separation H1s–H2s (negative where the planes are interchanged).
    grid : {"rectangular", "hexagonal"}
    cfa : {"none", "RGGB", "BGGR", "GRBG", "GBRG"}
    black_level : float
        Raw black level for TIFF/PNG captures (0 by default).
    white_level : float or None
        Raw white level for TIFF/PNG captures; ``None`` (the default) takes the file's own maximum
        (255 for 8-bit files, 65535 for 16-bit ones; camera raws always carry their own levels).
    micro_image_px : int or None
        Odd micro image size m̂ after resampling; ``None`` picks the largest odd integer not above
        ``mla_pitch_mm / lenslet_pixel_pitch_mm`` (``pixel_pitch_mm`` unless a microscope has a relay), and a
        measured micro image pitch may stand in for the nominal one (:attr:`m_hat` is the one in use).
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
    main_optics: MainOptics
    mla_principal_plane_gap_mm: float = 0.0
    grid: str = "rectangular"
    cfa: str = "none"
    black_level: float = 0.0
    white_level: float | None = None
    micro_image_px: int | None = None
    name: str = ""
    source: str = field(default="", compare=False, repr=False)
    provenance: tuple = field(default=(), compare=False, repr=False)

    def __post_init__(self):
        validate_camera(self)

    def __repr__(self) -> str:
        name = repr(self.name or self.source or "unnamed")
        return (f"<Camera {name}: {type(self.main_optics).__name__}, {self.m_hat}x{self.m_hat} views, MLA pitch "
                f"{self.mla_pitch_mm:g} mm f {self.mla_focal_length_mm:g} mm, pixels {self.pixel_pitch_mm:g} mm, "
                f"{self.grid}, CFA {self.cfa}>")

    def with_optics(self, main_optics: MainOptics) -> "Camera":
        """A copy with other main optics (e.g. ``camera.with_optics(replace(camera.main_optics,
        image_distance_mm=…))``); m̂ stays the camera's."""
        return replace(self, main_optics=main_optics)

    @property
    def micro_image_px_given(self) -> bool:
        """Whether m̂ was stated (``[decode] micro_image_px``, ``micro_image_px=``) rather than derived from the
        nominal pitch; a derived m̂ gives way to the measured micro image pitch (`lfproc.inputs.measured_m_hat`)."""
        return self.micro_image_px is not None

    # ----------------------------------------------------------------- derived quantities
    @property
    def m_hat(self) -> int:
        """Micro image size m̂ in pixels after resampling (odd): ``micro_image_px`` where stated, else the largest
        odd integer not above the nominal micro lens pitch in pixels (:attr:`pitch_px`)."""
        return int(self.micro_image_px) if self.micro_image_px is not None else largest_odd_at_most(self.pitch_px)

    @property
    def center_index(self) -> int:
        """c = (m̂ − 1) / 2, the index of the central view."""
        return (self.m_hat - 1) // 2

    @property
    def telecentric(self) -> bool:
        """True when the main optics' exit pupil is at infinity (the 2014 paper's model; always for a microscope)."""
        return math.isinf(self.main_optics.exit_pupil_distance_mm)

    @property
    def lenslet_pixel_pitch_mm(self) -> float:
        """The sensor pixel seen at the lenslets' focal plane: ``pixel_pitch_mm`` over the optics' relay."""
        return self.pixel_pitch_mm / float(self.main_optics.relay_magnification)

    @property
    def micro_image_scale(self) -> float:
        """(d_A + f_s) / d_A: the micro image centre lattice is the lens lattice scaled by this about the axis.

        Exactly 1.0 for a telecentric camera (Hahne et al. 2018: the chief ray through a lens centre
        comes from the exit pupil centre, so it lands f_s·s/d_A further out than the lens at height s).
        """
        if self.telecentric:
            return 1.0
        d_a = self.main_optics.exit_pupil_distance_mm
        return (d_a + self.mla_focal_length_mm) / d_a

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
