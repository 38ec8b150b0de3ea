"""The Airy limit (Eq. 22) against the effective pixel pitch: does diffraction or the pixel bound the DOF?"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Camera, MainLens
from ..errors import LfprocError, warn as warn_at_caller

#: default wavelength for the Airy limit (Eq. 22), in millimetres (550 nm)
DEFAULT_WAVELENGTH_MM = 550e-6


def airy_radius_mm(f_number, wavelength_mm: float = DEFAULT_WAVELENGTH_MM):
    """Radius of the Airy disk's central peak, (Δℓ)min ≈ 1.22·λ·f/A = 1.22·λ·N (Eq. 22)."""
    return 1.22 * wavelength_mm * np.asarray(f_number, dtype=np.float64)


@dataclass(frozen=True)
class DiffractionCheck:
    """Eq. 22 against the effective pixel pitch for the two apertures in the path.

    ``main_lens_airy_mm`` uses the main lens's working f-number b_U / D = N · b_U / f_U (the cone that
    converges on the micro lenses; ``None`` without an f-number); ``micro_lens_airy_mm``
    the micro lenses' working f-number f_s / p_m, which sets the spot every collimated beam forms on
    the sensor. ``pixel_limited`` is true when both are at most the effective pixel pitch: then the
    pixels, as the model assumes, bound the depth of field.
    """

    wavelength_mm: float
    effective_pixel_pitch_mm: float
    main_lens_airy_mm: float | None
    micro_lens_airy_mm: float
    pixel_limited: bool

    def message(self) -> str:
        parts = [f"micro lens Airy radius {self.micro_lens_airy_mm * 1e3:.2f} µm"]
        if self.main_lens_airy_mm is not None:
            parts.append(f"main lens Airy radius {self.main_lens_airy_mm * 1e3:.2f} µm")
        verdict = ("pixel-limited, as the model assumes" if self.pixel_limited else
                   "diffraction-limited: the optics, not the pixels, bound the DOF, which is then wider than predicted")
        return (f"{', '.join(parts)} vs effective pixel pitch {self.effective_pixel_pitch_mm * 1e3:.2f} µm at "
                f"{self.wavelength_mm * 1e6:.0f} nm: {verdict}")

    def record(self) -> dict:
        """The check as JSON-ready values (lengths in mm, ``None`` without an f-number)."""
        return dict(wavelength_mm=self.wavelength_mm, effective_pixel_pitch_mm=self.effective_pixel_pitch_mm,
                    main_lens_airy_mm=self.main_lens_airy_mm, micro_lens_airy_mm=self.micro_lens_airy_mm,
                    pixel_limited=self.pixel_limited, message=self.message())


def working_f_number(camera: Camera) -> float | None:
    """The main lens's working (image-side) f-number b_U / D, with D = f_U / N its entrance pupil's diameter.

    The Airy disk on the micro lenses (Eq. 22) follows the cone that converges there, whose f-number is
    N · b_U / f_U, not the object-side N (they agree only when focused at infinity, b_U = f_U).
    ``None`` without an f-number, and for other optics than a main lens (a microscope's aperture is the
    objective's NA, whose cone at the MLA this check does not report).
    """
    lens = camera.main_optics
    if not isinstance(lens, MainLens) or lens.f_number is None:    # the main lens's own Airy check (Eq. 22)
        return None
    return float(lens.f_number) * lens.image_distance_mm / lens.focal_length_mm


def diffraction_check(camera: Camera, wavelength_mm: float = DEFAULT_WAVELENGTH_MM,
                      warn: bool = True) -> DiffractionCheck:
    """Compare the Airy limit (Eq. 22) with the effective pixel pitch; warn when diffraction dominates."""
    if not (wavelength_mm > 0 and math.isfinite(wavelength_mm)):
        raise LfprocError(f"wavelength must be a positive number of millimetres, got {wavelength_mm}")
    pitch = camera.effective_pixel_pitch_mm
    working = working_f_number(camera)
    main = None if working is None else float(airy_radius_mm(working, wavelength_mm))
    micro = float(airy_radius_mm(camera.mla_focal_length_mm / camera.mla_pitch_mm, wavelength_mm))
    limited = micro <= pitch and (main is None or main <= pitch)
    check = DiffractionCheck(wavelength_mm, pitch, main, micro, limited)
    if warn and not limited:
        warn_at_caller(check.message(), DiffractionWarning)
    return check


class DiffractionWarning(UserWarning):
    """The Airy disk exceeds the effective pixel pitch: predicted DOFs are lower bounds."""
