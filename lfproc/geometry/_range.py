"""Which slices are real: the usable range of a, and the words of a refusal.

A refocused slice images a real object only where its chief rays meet in front of the camera at a real
object point (:mod:`._slices`, "Domain"). Which ``a`` those are is the main optics' business
(:meth:`lfproc.camera.MainOptics.usable_range`): for a main lens, with ε = b_U − f_U and δ = p_p / f_s, from
the slice at infinity a_∞ = −δ·ε/(p_m·(1 − κε)) (below it the rays diverge, "beyond infinity", or further
down meet between the main lens and its front focal plane) up to the front focal plane L + f_U, reached as
a → ∞ for a telecentric lens and at a = δ/(p_m·κ) with a finite exit pupil (κ = 1/d_A > 0); an afocal
objective images every depth, of either sign: no limit.

A capture narrows the range further (a slice shifted so far that most of it falls off the capture is no
image: ``lfproc.refocusing.usable_a_bound``). Every refusal of one capture states one usable range, the
narrower of the two, low to high, in the terms of the argument the user gave: ``a`` with each end's position,
or a position (``distance_mm``, ``z_um``) with each end's ``a``.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LfprocError
from ._slices import SENSOR_MM, _pair_position, require_space

#: relative tolerance on the bounds (a typed from a printed bound, or a_∞ recomputed by another formula)
_TOLERANCE = 1e-9


def front_focal_plane_mm(camera) -> float:
    """L + f_U: the main lens's front focal plane, in mm from the sensor (no real image nearer): the near end of
    the optics' usable range."""
    require_space(camera, SENSOR_MM, "the front focal plane")
    return camera.main_optics.usable_range(camera).high_position


def usable_a_range(camera, a_low: float | None = None, a_high: float | None = None) -> tuple[float, float]:
    """(a_low, a_high): the refocus parameters of real slices (:meth:`lfproc.camera.MainOptics.usable_range`),
    narrowed to ``a_low`` … ``a_high`` where given (e.g. the slices whose refocused area covers half a capture).

    A main lens: a_∞ (at infinity) to its front focal plane (``inf`` when telecentric, δ/(p_m·κ) with a finite
    exit pupil); an afocal objective: ``(-inf, inf)``.
    """
    usable = camera.main_optics.usable_range(camera)
    low = usable.low if a_low is None else max(usable.low, float(a_low))
    high = usable.high if a_high is None else min(usable.high, float(a_high))
    return low, max(high, low)


def slice_positions(camera, a) -> np.ndarray | float:
    """Object-space position of the slices ``a`` for any ``a`` (±inf included): inside the optics' usable range
    the slice's position (:func:`~._slices.slice_geometry`'s ``depth``); at or beyond an end, that end's
    position (a main lens: a ≤ a_∞ at infinity, a → ∞ at its front focal plane; an objective: ±inf at ±inf).
    """
    usable = camera.main_optics.usable_range(camera)
    a = np.asarray(a, dtype=np.float64)
    safe = np.where(np.isfinite(a), np.clip(a, usable.low, usable.high), 0.0)
    position = np.asarray(_pair_position(camera, safe, safe)[0], dtype=np.float64)
    position = np.where(a <= usable.low, usable.low_position, position)
    position = np.where(a >= usable.high, usable.high_position, position)
    return float(position) if position.ndim == 0 else position


def format_a(value: float, inward: int = 0) -> str:
    """``a`` for a message: signed, at most 3 decimals, rounded towards the inside of a range
    (``inward`` +1 for a lower bound, −1 for an upper bound) so that the printed bound is usable."""
    if not math.isfinite(value):
        return "+inf" if value > 0 else "-inf"
    scaled = value * 1000.0
    scaled = math.ceil(scaled - 1e-6) if inward > 0 else math.floor(scaled + 1e-6) if inward < 0 else round(scaled)
    text = f"{scaled / 1000.0 + 0.0:+.3f}".rstrip("0").rstrip(".")
    return text


def usable_range_text(camera, a_low: float | None = None, a_high: float | None = None, name: str = "a") -> str:
    """One usable range low to high, each end with where it focuses: ``"a from +0 (infinity) to +4 (206.7 mm)"``.

    Without bounds, the optics' own (:func:`usable_a_range`); given bounds are narrowed to it. The printed ends
    are rounded inwards, so they can be typed back. ``name``: the argument the user gave; a position key
    (``distance_mm``, ``z_um``, … of the optics' object space) gives the range in positions low to high, each
    with its ``a``: ``"distance_mm from 206.7 mm (a=+4) to infinity (a=+0)"``.
    """
    usable = camera.main_optics.usable_range(camera)
    space = camera.main_optics.object_space
    low, high = usable_a_range(camera, a_low, a_high)
    ends = []
    for a, own, own_position, inward in ((low, usable.low, usable.low_position, +1),
                                         (high, usable.high, usable.high_position, -1)):
        text = format_a(a, inward)
        if a == own:
            position = own_position
        else:
            position = float(_pair_position(camera, float(text), float(text))[0])
        ends.append((text, position))
    if name == "a":
        return " to ".join(f"{text} ({_position_text(space, position, text, usable)})" for text, position in
                           ends).join(("a from ", ""))
    (low_a, low_position), (high_a, high_position) = sorted(ends, key=lambda end: end[1])
    return (f"{name} from {_plain(space, low_position)} to {_plain(space, high_position)} (a from {low_a} to "
            f"{high_a})")


def _plain(space, position: float) -> str:
    """A position with its unit and no name: ``"176.2 mm"``, ``"infinity"``, ``"-66.31 µm"``."""
    if math.isinf(position):
        return "infinity" if position > 0 and space.toward_optics < 0 else f"{position:+} {space.symbol}"
    return f"{position:{space.spec}} {space.symbol}"


def _position_text(space, position: float, a_text: str, usable) -> str:
    """Where a range end focuses; an unbounded ``a`` only approaches its position (the near end, in words)."""
    if a_text in ("+inf", "-inf") and math.isfinite(position):
        return f"approaching {usable.high_name + ' at ' if usable.high_name else ''}{space.text(position)}"
    return space.text(position)


def _outside(camera, a_values, a_low=None, a_high=None) -> np.ndarray:
    """Indices of the ``a_values`` outside the usable range (narrowed to ``a_low``/``a_high`` if given)."""
    a = np.atleast_1d(np.asarray(a_values, dtype=np.float64))
    low, high = usable_a_range(camera, a_low, a_high)
    tol_lo = _TOLERANCE * max(1.0, abs(low)) if math.isfinite(low) else 0.0
    tol_hi = _TOLERANCE * max(1.0, abs(high)) if math.isfinite(high) else 0.0
    return np.flatnonzero(~((a >= low - tol_lo) & (a <= high + tol_hi)))


def check_usable_a(camera, a_values, what: str = "a", a_low: float | None = None, a_high: float | None = None,
                   asked=None, source: str | None = None) -> None:
    """Refuse refocus parameters whose slices image no real object (beyond infinity, nearer than a main lens's
    front focal plane).

    Parameters
    ----------
    camera : Camera
    a_values : float or array_like
        The slices asked for; all are checked before any work (a sweep partly outside is refused).
    what : str
        The argument the values came from, as the caller's user knows it (``"--a"``, ``"a"``, ``"z_um"``).
    a_low, a_high : float, optional
        Where a capture narrows the usable range (its refocused area): the message states that one range.
    asked : array_like, optional
        The values as the user gave them, in the unit ``what`` names (positions, where ``what`` is a position
        key); the message then speaks in them and gives the range in positions.
    source : str, optional
        The capture the slices are of: the message starts with it (as a refusal of its refocused area does)
        instead of ``what``.

    Raises
    ------
    LfprocError
        One line: the first refused value, why, and the one usable range low to high.
    """
    a = np.atleast_1d(np.asarray(a_values, dtype=np.float64))
    bad = _outside(camera, a)
    if not len(bad):
        return
    value = float(a[bad[0]])
    why = camera.main_optics.refusal(camera, value)
    count = f" ({len(bad)} of the {len(a)} slices)" if len(a) > 1 else ""
    name = _name(camera, what)
    space = camera.main_optics.object_space
    given = f"a={value:g}" if asked is None else f"{what}={np.atleast_1d(asked)[bad[0]]:g} {space.symbol}"
    raise LfprocError(f"{source or what}: {given} {why}{count}; usable: "
                      f"{usable_range_text(camera, a_low, a_high, name)}")


def _name(camera, what: str) -> str:
    """The range's terms for an argument ``what``: the optics' position key where ``what`` is it (``z_um``,
    ``distance_mm``), else ``a``."""
    return what if what == camera.main_optics.object_space.position_key else "a"


def check_usable_distances(camera, distances_mm, what: str = "distance_mm") -> None:
    """Refuse distances (mm from the sensor) at or nearer than the front focal plane, or not numbers.

    Infinity is a real slice (the one at a_∞). The message gives the usable range in distances, as
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
