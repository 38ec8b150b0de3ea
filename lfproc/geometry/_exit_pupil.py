"""The finite exit pupil (Hahne et al., IJCV 2018; PlenoptiSign's d_A): micro image drift and its inverse.

With the exit pupil d_A in front of the micro lens array, the chief ray through the centre of a
micro lens at height s comes from the pupil centre on the axis, so the micro image centre lands at
u_c = s·(d_A + f_s)/d_A on the sensor: the micro image lattice is the lens lattice scaled by
``(d_A + f_s)/d_A`` about the optical axis. A pixel i samples from its micro image centre then sees
the image-side chief-ray slope m = −s/d_A − i·p_p/f_s (the first term is what the telecentric model
of 2014 leaves out). ``κ = 1/d_A`` (0 when telecentric) carries the correction through every formula,
so that an infinite d_A gives exactly the telecentric numbers.
"""

from __future__ import annotations

import numpy as np

from ..camera import Camera
from ..errors import LfprocError


def pupil_curvature(camera: Camera) -> float:
    """κ = 1/d_A in 1/mm: the slope change per mm of lens height; exactly 0.0 for a telecentric camera."""
    return 0.0 if camera.telecentric else 1.0 / camera.main_optics.exit_pupil_distance_mm


def micro_image_scale(camera: Camera) -> float:
    """(d_A + f_s)/d_A: the scale of the micro image centre lattice about the optical axis (1.0 telecentric).

    Calibration fits micro image centres (what a white image shows); their pitch is the micro lens
    pitch times this scale.
    """
    return camera.micro_image_scale


def exit_pupil_from_scale(scale, camera: Camera):
    """d_A = f_s/(scale − 1): the exit pupil distance that a fitted micro image lattice scale implies.

    Parameters
    ----------
    scale : float or array_like
        Fitted micro image pitch over the micro lens pitch (from calibration and ``mla.pitch_mm``).
    camera : Camera
        Supplies f_s.

    Returns
    -------
    float or ndarray
        In mm from the micro lens array; ``inf`` for a scale of 1 or below: no outward drift (a fitted
        scale a little below 1 is fit noise on a telecentric camera; an inward drift would need an exit
        pupil behind the sensor, which no plenoptic camera's main lens has).

    Raises
    ------
    LfprocError
        For a non-finite or non-positive scale.
    """
    s = np.asarray(scale, dtype=np.float64)
    if np.any(~np.isfinite(s)) or np.any(s <= 0):
        bad = s[~np.isfinite(s) | (s <= 0)].ravel()[0]
        raise LfprocError(f"micro image lattice scale {bad} is not a positive number; check the calibrated pitch "
                          f"against mla.pitch_mm")
    with np.errstate(divide="ignore"):
        d_a = np.where(s > 1.0, camera.mla_focal_length_mm / np.maximum(s - 1.0, np.finfo(float).tiny), np.inf)
    return float(d_a) if d_a.ndim == 0 else d_a
