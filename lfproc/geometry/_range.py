"""Which slices are real: the usable range of a, from the slice at infinity to the front focal plane.

A refocused slice images a real object only where its chief rays meet in front of the camera,
beyond the main lens's front focal plane (:mod:`._slices`, "Domain"). With ε = b_U − f_U and
δ = p_p / f_s, the slice at infinity is a_∞ = −δ·ε/(p_m·(1 − κε)) (:func:`infinity_parameter`); below
it the rays diverge (the slice is "beyond infinity", distance ``inf``) or, further down, meet between
the main lens and its front focal plane, where no object forms a real image. Above a_∞ the distance
falls monotonically towards the front focal plane L + f_U, which it reaches only as a → ∞ for a
telecentric main lens; with a finite exit pupil (κ = 1/d_A > 0) at a = δ/(p_m·κ), where the slope
step N = δ − a·p_m·κ of Eq. 16's pair vanishes. So the usable slices are a_∞ ≤ a < a_ffp, distances
from infinity down to the front focal plane.

Main optics whose object space is signed depths about a native object plane (an afocal objective,
:attr:`~lfproc.camera.ObjectSpace.from_sensor` False) image every depth, of either sign: no such limit.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LfprocError
from ._exit_pupil import pupil_curvature
from ._slices import _pair_position, infinity_parameter, slice_distance_mm

#: relative tolerance on the bounds (a typed from a printed bound, or a_∞ recomputed by another formula)
_TOLERANCE = 1e-9


def front_focal_plane_mm(camera) -> float:
    """L + f_U: the main lens's front focal plane, in mm from the sensor (no real image nearer)."""
    return camera.sensor_to_main_lens_mm + camera.main_focal_length_mm


def usable_a_range(camera) -> tuple[float, float]:
    """(a_low, a_high): the refocus parameters of real slices, a_∞ (at infinity) to the front focal plane.

    ``a_high`` is ``inf`` for a telecentric main lens (the front focal plane is reached only in the
    limit) and δ/(p_m·κ) with a finite exit pupil in front of the MLA (module docstring). Optics that report
    signed depths (a microscope) have no such bounds: ``(-inf, inf)``.
    """
    if not camera.object_space.from_sensor:   # an afocal objective has no slice at infinity, no front focal plane
        return -math.inf, math.inf
    low = float(infinity_parameter(camera))
    kappa = pupil_curvature(camera)
    high = math.inf
    if kappa > 0:
        high = camera.sample_pitch_mm / camera.mla_focal_length_mm / (camera.mla_pitch_mm * kappa)
    return low, max(high, low)


def format_a(value: float, inward: int = 0) -> str:
    """``a`` for a message: signed, at most 3 decimals, rounded towards the inside of a range
    (``inward`` +1 for a lower bound, −1 for an upper bound) so that the printed bound is usable."""
    if not math.isfinite(value):
        return "+inf" if value > 0 else "-inf"
    scaled = value * 1000.0
    scaled = math.ceil(scaled - 1e-6) if inward > 0 else math.floor(scaled + 1e-6) if inward < 0 else round(scaled)
    text = f"{scaled / 1000.0 + 0.0:+.3f}".rstrip("0").rstrip(".")
    return text


def _where(camera, a: float) -> str:
    """Where slice ``a`` focuses, for a message, in the camera's object space: ``"206.7 mm"``, ``"infinity"``
    (from the sensor), a signed depth ``"z = +1.5 um"`` (from a microscope's native object plane)."""
    space = camera.object_space
    if space.from_sensor and math.isinf(a):
        return f"approaching the front focal plane at {front_focal_plane_mm(camera):.1f} mm"
    position = float(_pair_position(camera, a, a)[0])       # the slice's centre, as slice_geometry's depth
    if not space.from_sensor:
        return f"z = {position:+.4g} {space.symbol}"
    return "infinity" if math.isinf(position) else f"{position:.1f} {space.symbol}"


def usable_range_text(camera, a_low: float | None = None, a_high: float | None = None) -> str:
    """``"a from +0 (infinity) to +4 (206.7 mm)"``: a usable range low-to-high in a, each end's distance.

    Without bounds, the camera's own (:func:`usable_a_range`); given bounds (e.g. those of the refocused
    area) are narrowed to it. The printed ends are rounded inwards, so they can be typed back.
    """
    low, high = usable_a_range(camera)
    at_infinity = a_low is None or float(a_low) <= low
    if a_low is not None:
        low = max(low, float(a_low))
    if a_high is not None:
        high = min(high, float(a_high))
    lo_text, hi_text = format_a(low, +1), format_a(high, -1)
    far = ("infinity" if at_infinity and camera.object_space.from_sensor   # signed depths have no infinity
           else _where(camera, float(lo_text)))
    return (f"a from {lo_text} ({far}) to "
            f"{hi_text} ({_where(camera, float(hi_text) if math.isfinite(high) else high)})")


def _outside(camera, a_values, a_low=None, a_high=None) -> np.ndarray:
    """Indices of the ``a_values`` outside the usable range (narrowed to ``a_low``/``a_high`` if given)."""
    a = np.atleast_1d(np.asarray(a_values, dtype=np.float64))
    low, high = usable_a_range(camera)
    if a_low is not None:
        low = max(low, float(a_low))
    if a_high is not None:
        high = min(high, float(a_high))
    tol_lo = _TOLERANCE * max(1.0, abs(low)) if math.isfinite(low) else 0.0
    tol_hi = _TOLERANCE * max(1.0, abs(high)) if math.isfinite(high) else 0.0
    return np.flatnonzero(~((a >= low - tol_lo) & (a <= high + tol_hi)))


def check_usable_a(camera, a_values, what: str = "a") -> None:
    """Refuse refocus parameters that focus beyond infinity or nearer than the front focal plane.

    Parameters
    ----------
    camera : Camera
    a_values : float or array_like
        The slices asked for; all are checked before any work (a sweep partly outside is refused).
    what : str
        The argument the values came from, as the caller's user knows it (``"--a"``, ``"a"``).

    Raises
    ------
    LfprocError
        One line: the first refused a, why, and the whole usable range low-to-high in a and in distance.
    """
    a = np.atleast_1d(np.asarray(a_values, dtype=np.float64))
    bad = _outside(camera, a)
    if not len(bad):
        return
    value = float(a[bad[0]])
    low, _ = usable_a_range(camera)
    d = float(slice_distance_mm(camera, value))
    front = front_focal_plane_mm(camera)
    if value < low and not (math.isfinite(d) and d <= front):
        why = "focuses beyond infinity (its rays diverge: no object is imaged there)"
    else:
        where = f"{d:.1f} mm from the sensor, " if math.isfinite(d) else ""
        why = (f"focuses {where}nearer than the main lens's front focal plane ({front:.1f} mm), where no object "
               f"forms a real image")
    count = f" ({len(bad)} of the {len(a)} slices)" if len(a) > 1 else ""
    raise LfprocError(f"{what}: a={value:g} {why}{count}; usable: {usable_range_text(camera)}")


def check_usable_distances(camera, distances_mm, what: str = "distance_mm") -> None:
    """Refuse distances (mm from the sensor) at or nearer than the front focal plane, or not numbers.

    Infinity is a real slice (the one at a_∞). The message gives the usable range as
    :func:`check_usable_a` does.
    """
    d = np.atleast_1d(np.asarray(distances_mm, dtype=np.float64))
    front = front_focal_plane_mm(camera)
    bad = np.flatnonzero(np.isnan(d) | (d <= front))
    if not len(bad):
        return
    raise LfprocError(f"{what}: {d[bad[0]]:g} mm is not beyond the main lens's front focal plane ({front:.1f} mm "
                      f"from the sensor): nothing there forms a real image to focus on; usable: distances beyond "
                      f"{front:.1f} mm up to infinity, i.e. {usable_range_text(camera)}")
