"""Checks of a Camera's values, with one-line messages that name the camera file key and the fix."""

from __future__ import annotations

import math

from ..errors import LfprocError
from ._optics import ODD_TOLERANCE, largest_odd_at_most

GRIDS = ("rectangular", "hexagonal")
CFA_PATTERNS = ("none", "RGGB", "BGGR", "GRBG", "GBRG")
#: dataclass field -> the key a user writes in the camera file (for error messages)
TOML_KEYS = {
    "pixel_pitch_mm": "sensor.pixel_pitch_mm", "black_level": "sensor.black_level",
    "white_level": "sensor.white_level", "mla_pitch_mm": "mla.pitch_mm",
    "mla_focal_length_mm": "mla.focal_length_mm", "mla_principal_plane_gap_mm": "mla.principal_plane_gap_mm",
    "main_focal_length_mm": "main_lens.focal_length_mm",
    "main_principal_plane_gap_mm": "main_lens.principal_plane_gap_mm",
    "image_distance_mm": "main_lens.image_distance_mm", "f_number": "main_lens.f_number",
    "exit_pupil_distance_mm": "main_lens.exit_pupil_distance_mm",
}


def validate_camera(camera) -> int:
    """Raise `LfprocError` for an impossible camera; return the micro image size m̂ to store.

    ``micro_image_px`` = None picks the largest odd integer not above ``mla_pitch_mm / pixel_pitch_mm``.
    """
    where = camera.source or "camera"
    for key in ("pixel_pitch_mm", "mla_pitch_mm", "mla_focal_length_mm"):
        require_positive(getattr(camera, key), key, where)
    for key in ("mla_principal_plane_gap_mm", "main_principal_plane_gap_mm", "black_level"):
        require_finite(getattr(camera, key), key, where)
    if camera.microscope is not None:
        _validate_microscope(camera, where)
    else:
        if camera.main_focal_length_mm is None or camera.image_distance_mm is None:
            raise LfprocError(f"{where}: a camera needs a main lens (main_lens.focal_length_mm and "
                              f"image_distance_mm) or a [microscope] table; add one")
        require_positive(camera.main_focal_length_mm, "main_focal_length_mm", where)
        require_finite(camera.image_distance_mm, "image_distance_mm", where)
    if camera.white_level is not None:
        require_finite(camera.white_level, "white_level", where)
    d_a = camera.exit_pupil_distance_mm
    if isinstance(d_a, bool) or not isinstance(d_a, (int, float)) or math.isnan(d_a) or d_a <= 0:
        raise LfprocError(f"{where}: main_lens.exit_pupil_distance_mm must be a positive distance or inf, "
                          f"got {d_a!r}")
    if camera.f_number is not None:
        require_positive(camera.f_number, "f_number", where)
    if camera.microscope is None and camera.image_distance_mm < camera.main_focal_length_mm:
        raise LfprocError(
            f"{where}: main_lens.image_distance_mm = {camera.image_distance_mm} is below the main lens focal length "
            f"{camera.main_focal_length_mm}, so the main lens would focus beyond infinity; "
            f"set image_distance_mm >= focal_length_mm (or give focus_distance_mm)")
    if camera.grid not in GRIDS:
        raise LfprocError(f"{where}: unknown mla.grid {camera.grid!r}; use one of {', '.join(GRIDS)}")
    if camera.cfa not in CFA_PATTERNS:
        raise LfprocError(f"{where}: unknown sensor.cfa {camera.cfa!r}; use one of {', '.join(CFA_PATTERNS)}")
    if camera.white_level is not None and camera.white_level <= camera.black_level:
        raise LfprocError(f"{where}: white_level {camera.white_level} must exceed black_level {camera.black_level}")
    _validate_provenance(camera.provenance, where)
    if getattr(camera, "main_lens_prescription", None) is not None:
        _validate_prescription(camera, where)
    ratio = camera.mla_pitch_mm / camera.lenslet_pixel_pitch_mm
    if not math.isfinite(ratio):  # e.g. 1e300 mm over 1e-10 mm
        raise LfprocError(f"{where}: mla.pitch_mm / sensor.pixel_pitch_mm = {camera.mla_pitch_mm} / "
                          f"{camera.pixel_pitch_mm} is not a finite number of pixels; check both pitches")
    if camera.micro_image_px is None:
        if ratio < 1.0 - ODD_TOLERANCE:
            raise LfprocError(f"{where}: the micro lens pitch {camera.mla_pitch_mm} mm is smaller than one pixel "
                              f"({camera.lenslet_pixel_pitch_mm} mm); check the units of both pitches")
        return largest_odd_at_most(ratio)
    m = camera.micro_image_px
    if isinstance(m, bool) or not isinstance(m, int) or m < 1 or m % 2 == 0:
        raise LfprocError(f"{where}: decode.micro_image_px must be an odd integer >= 1, got {m!r}; "
                          f"try {largest_odd_at_most(max(ratio, 1.0))}")
    return m


def _validate_microscope(camera, where: str) -> None:
    """A microscope has no main lens: no f_U, b_U, f-number or exit pupil may be set beside it."""
    from ._microscope import Microscope
    if not isinstance(camera.microscope, Microscope):
        raise LfprocError(f"{where}: microscope must be a Microscope, got {camera.microscope!r}")
    if (camera.main_focal_length_mm is not None or camera.image_distance_mm is not None
            or camera.f_number is not None or camera.main_principal_plane_gap_mm != 0.0
            or not math.isinf(camera.exit_pupil_distance_mm)):
        raise LfprocError(f"{where}: a microscope camera has no main lens; give [microscope] or [main_lens], not both")
    camera.microscope.validate(where)


def _validate_prescription(camera, where: str) -> None:
    """f_U, H1U–H2U and d_A of a camera with a prescription are the lens's own (within 0.1 %)."""
    from ._lens import PRESCRIPTION_TOLERANCE, LensPrescription
    lens = camera.main_lens_prescription
    if not isinstance(lens, LensPrescription):
        raise LfprocError(f"{where}: main_lens_prescription must be a LensPrescription, got {lens!r}")
    if camera.microscope is not None:
        raise LfprocError(f"{where}: a microscope camera has no main lens prescription")
    for key, value, lens_value in (
            ("main_focal_length_mm", camera.main_focal_length_mm, lens.focal_length_mm),
            ("main_principal_plane_gap_mm", camera.main_principal_plane_gap_mm, lens.principal_plane_gap_mm),
            ("exit_pupil_distance_mm", camera.exit_pupil_distance_mm,
             lens.exit_pupil_distance_mm(camera.image_distance_mm))):
        same = (value == lens_value if math.isinf(value) or math.isinf(lens_value)
                else abs(value - lens_value) <= PRESCRIPTION_TOLERANCE * max(abs(lens_value), 1e-3))
        if not same:
            raise LfprocError(f"{where}: {TOML_KEYS[key]} = {value} disagrees with the prescription's {lens_value:.6g} "
                              f"(more than 0.1 %); use Camera.with_main_lens or fix the value")


def _validate_provenance(provenance, where: str) -> None:
    if not isinstance(provenance, tuple) or not all(
            isinstance(p, tuple) and len(p) == 2 and all(isinstance(s, str) for s in p) for p in provenance):
        raise LfprocError(f"{where}: provenance must be a tuple of (key, text) string pairs, got {provenance!r}")


def require_positive(value, key: str, where: str) -> None:
    """A finite number > 0, else a one-line error naming the camera file key."""
    key = TOML_KEYS.get(key, key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise LfprocError(f"{where}: {key} must be a finite positive number, got {value!r}")


def require_finite(value, key: str, where: str) -> None:
    """A finite number, else a one-line error naming the camera file key."""
    key = TOML_KEYS.get(key, key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise LfprocError(f"{where}: {key} must be a finite number, got {value!r}")
