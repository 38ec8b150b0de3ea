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
}


def validate_camera(camera) -> int:
    """Raise `LfprocError` for an impossible camera; return the micro image size m̂ to store.

    ``micro_image_px`` = None picks the largest odd integer not above ``mla_pitch_mm / pixel_pitch_mm``.
    """
    where = camera.source or "camera"
    for key in ("pixel_pitch_mm", "mla_pitch_mm", "mla_focal_length_mm"):
        require_positive(getattr(camera, key), key, where)
    for key in ("mla_principal_plane_gap_mm", "black_level"):
        require_finite(getattr(camera, key), key, where)
    if camera.main_optics is None or not callable(getattr(camera.main_optics, "validate", None)):
        raise LfprocError(f"{where}: a camera needs main optics (a [main_lens] or [microscope] table, or "
                          f"main_optics= a MainLens or Microscope), got {camera.main_optics!r}; add one")
    camera.main_optics.validate(where)
    if camera.white_level is not None:
        require_finite(camera.white_level, "white_level", where)
    if camera.grid not in GRIDS:
        raise LfprocError(f"{where}: unknown mla.grid {camera.grid!r}; use one of {', '.join(GRIDS)}")
    if camera.cfa not in CFA_PATTERNS:
        raise LfprocError(f"{where}: unknown sensor.cfa {camera.cfa!r}; use one of {', '.join(CFA_PATTERNS)}")
    if camera.white_level is not None and camera.white_level <= camera.black_level:
        raise LfprocError(f"{where}: white_level {camera.white_level} must exceed black_level {camera.black_level}")
    _validate_provenance(camera.provenance, where)
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
