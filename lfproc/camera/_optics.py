"""Closed-form helpers of the camera model that need no Camera: m̂ from the pitches, b_U from a focus distance."""

from __future__ import annotations

import math

from ..errors import LfprocError

#: a pitch ratio within this relative distance of an odd integer counts as that integer
ODD_TOLERANCE = 1e-6


def largest_odd_at_most(ratio: float) -> int:
    """Largest odd integer not above ``ratio``; a ratio within 1e-6 of an odd integer counts as it.

    This is the contract's default micro image size m̂ for ``pitch_mm / pixel_pitch_mm``.
    """
    nearest = round(ratio)
    if nearest % 2 == 1 and abs(ratio - nearest) <= ODD_TOLERANCE * max(1.0, ratio):
        return int(nearest)
    m = int(math.floor(ratio))
    if m % 2 == 0:
        m -= 1
    return max(m, 1)


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
    where : str
        The file or object named in error messages.
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
