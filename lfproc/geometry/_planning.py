"""Slice planning: the fewest refocus parameters whose DOF intervals cover a range of depths, and what they miss.

Positions are in the main optics' own object space (mm from the sensor for a main lens, µm from the native
object plane for a microscope, :attr:`lfproc.camera.MainOptics.object_space`): a range is given by its end
nearer to the optics and its end farther from them, and planning runs from the far end towards the optics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ._exit_pupil import pupil_curvature
from ._slices import _lit_view_extent, _slope_step, _view_extent, position_parameter, slice_geometry

#: the most slices one request may render (``--a`` lists and ``--depth-range`` alike); pass
#: ``max_slices`` to go beyond it
MAX_SLICES = 10000


@dataclass(frozen=True, eq=False)
class SlicePlan:
    """The slices planned for a depth range and the depths they leave out of focus.

    Attributes
    ----------
    a : ndarray of float
        Refocus parameters, far slice first (increasing ``a``).
    uncovered : tuple of (near, far, reason)
        Depth intervals of the request that no planned slice's DOF covers, nearest last, each with
        a one-line reason (a gap allowed by ``max_gap`` or ``integer``, the slice limit, or the
        part of the range no slice can focus on); positions in the optics' object space.
    """

    a: np.ndarray
    uncovered: tuple

    @property
    def complete(self) -> bool:
        """True when every depth of the request lies in some slice's DOF."""
        return not self.uncovered


def _slice_for_far_limit(camera: Camera, target: float, view_extent=None) -> float:
    """The ``a`` whose far DOF limit is ``target``: inverts a₊ of :func:`slice_geometry` (c → r, view_extent) and
    the half wave term the optics add."""
    c = _view_extent(camera, view_extent) if view_extent is not None else _lit_view_extent(camera)
    optics = camera.main_optics
    space = optics.object_space
    a_limit = position_parameter(camera, target + space.toward_optics * (0.5 * optics.wave_depth_of_field()))
    ratio = camera.mla_pitch_mm * pupil_curvature(camera) / _slope_step(camera)
    if a_limit >= 0:   # limit at or in front of the focus distance: A = (2ac − 1)/(2c + 1)
        a = (a_limit * (1.0 - ratio / (2.0 * c + 1.0)) * (2.0 * c + 1.0) + 1.0) / (2.0 * c)
    else:              # beyond it the bounding pair is A = (2ac − 1)/(2c − 1)
        a = (a_limit * (1.0 - ratio / (2.0 * c - 1.0)) * (2.0 * c - 1.0) + 1.0) / (2.0 * c)
    # Near infinity a₊ cancels digits, so the far limit of that a can fall short of the target (or stay
    # finite for a target at infinity). Lower a by doubling steps from the rounding of a₊ until it reaches:
    # the far limit never comes nearer as a falls, so this ends, overshooting by < 2 steps.
    step = 2.0 ** -52 * (abs(a) + 1.0 / (2.0 * c))
    for _ in range(2000):
        if not space.is_nearer(slice_geometry(camera, a, view_extent).far, target):
            break
        a -= step
        step *= 2.0
    return a


def usable_end(camera) -> str:
    """The nearest any slice of the camera focuses, in words (``"the main lens's front focal plane (100.4 mm)"``)."""
    return camera.main_optics.usable_range(camera).near_end(camera.main_optics.object_space)


def _check_request(camera: Camera, near: float, far: float, max_gap: float, view_extent, what: str) -> float:
    """Refuse an impossible request; return the nearest position any slice focuses at (the usable range's end)."""
    space = camera.main_optics.object_space
    if camera.center_index == 0:
        raise LfprocError("depth-range planning needs micro images of 3 px or more (micro_image_px >= 3)")
    if _view_extent(camera, view_extent) == 0:
        raise LfprocError("depth-range planning needs more than the central view summed (one view does not "
                          "refocus); give a wider `aperture=`")
    if not (space.holds(near) and space.holds(far) and (near == far or space.is_nearer(near, far))):
        raise LfprocError(f"{what}{near}:{far} {space.symbol} is not a valid range; give NEAR:FAR {space.origin}, "
                          f"NEAR at or nearer than FAR")
    if not (max_gap >= 0 and math.isfinite(max_gap)):
        raise LfprocError(f"the largest allowed DOF gap must be a finite number of {space.symbol} >= 0, got {max_gap}")
    return camera.main_optics.usable_range(camera).high_position


def _greedy(camera, near, far, max_gap, integer, max_slices, view_extent=None):
    """The greedy plan of :func:`plan_slices`; returns (slices, edge, why it stopped early or None)."""
    space = camera.main_optics.object_space
    slices: list[float] = []
    edge = far                      # everything beyond the edge is covered (or an allowed gap)
    target = space.beyond(far)      # every target a hair beyond, so rounding never leaves a sliver uncovered
    while True:
        a = _slice_for_far_limit(camera, target, view_extent)
        if integer:  # the largest integer whose far limit still reaches the target (far comes nearer with a)
            a = float(math.floor(a + 1e-9))
            if slices and a <= slices[-1]:
                a = slices[-1] + 1.0
            if not space.is_nearer(float(slice_geometry(camera, a, view_extent).near), edge):
                a += 1.0  # its interval lies wholly beyond the edge: the next integer makes progress
        reached = float(slice_geometry(camera, a, view_extent).near)
        if space.is_nearer(edge, reached) and not integer:   # DOF narrower than the overlap: no progress possible
            return slices, edge, "thin"
        slices.append(a)
        edge = float(space.nearer(edge, reached))
        if not space.is_nearer(near, edge):
            return slices, edge, None
        if len(slices) >= max_slices:
            return slices, edge, "limit"
        target = space.beyond(float(space.farther(edge + space.toward_optics * max_gap, near)))


def _even(camera, near, far, step, max_slices, what) -> np.ndarray:
    """Slices at evenly spaced positions from the low end to the high end of [near, far], ``step`` apart."""
    space = camera.main_optics.object_space
    lo, hi = (float(v) for v in space.low_high(near, far))
    if not (math.isfinite(step) and step > 0):
        raise LfprocError(f"{what}{near}:{far}:{step}: the step must be a positive number of {space.symbol}")
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise LfprocError(f"{what}{near}:{far}:{step}: evenly spaced slices need two finite ends")
    count = int(math.floor((hi - lo) / step + 1e-9)) + 1
    if count > max_slices:
        raise LfprocError(f"{what}{near}:{far}:{step} asks for {count} slices, more than {max_slices}; use a larger "
                          f"step")
    return np.atleast_1d(position_parameter(camera, lo + step * np.arange(count)))


def plan_slices(camera: Camera, near: float, far: float, *, max_gap: float = 0.0, integer: bool = False,
                max_slices: int = MAX_SLICES, view_extent=None, step: float | None = None,
                what: str = "depth range ") -> np.ndarray:
    """The fewest refocus parameters whose [near, far] DOF intervals together cover the range [near, far].

    Greedy from the far end, which is optimal for intervals whose both ends come nearer with ``a``:
    each slice is the one whose far limit sits exactly on the nearest point not yet covered, so its
    near limit reaches as close as any slice covering that point can. Neighbouring intervals touch
    (with a 1e-9 overlap against rounding), so no depth in the range is left out of focus.

    Two ways to compute less, when the scene allows:

    * ``max_gap`` > 0 tolerates uncovered depths up to that size *between* slices (never at the
      ends of the range): the next slice's far limit may sit that much nearer, so fewer slices.
    * ``integer=True`` uses integer ``a`` only — pure gathers, no interpolation, the cheapest slices —
      and leaves the gaps between integer slices that the paper points out (Section 5.2). Where even
      the next integer cannot keep a gap within ``max_gap`` it is taken anyway; check the result
      with :func:`uncovered_depths`.

    This strict form refuses a range it cannot cover whole; :func:`plan_depth_range` plans what can
    be covered and names the rest.

    Parameters
    ----------
    camera : Camera
        Needs m̂ ≥ 3 (a single-pixel micro image cannot refocus).
    near, far : float
        The range's ends nearer to and farther from the optics, in their object space (mm from the sensor
        for a main lens, where ``far`` may be ``inf``; µm from the native object plane for a microscope).
    max_gap : float
        Largest uncovered depth interval allowed between slices.
    integer : bool
        Plan integer refocus parameters only.
    max_slices : int
        Guard against ranges that would need absurdly many slices (default :data:`MAX_SLICES`).
    view_extent : int, optional
        Half-extent of the views the slices will average (:func:`slice_geometry`); the views the optics fill
        when ``None``.
    step : float, optional
        Instead of the fewest covering slices, slices at evenly spaced positions ``step`` apart from the
        range's low end (an evenly spaced z-stack).
    what : str
        How the caller's user names the range in messages (``"depth range "``, ``"z_range_um="``).

    Returns
    -------
    ndarray of float
        Refocus parameters, far slice first (increasing ``a``).
    """
    space = camera.main_optics.object_space
    closest = _check_request(camera, near, far, max_gap, view_extent, what)
    if step is not None:
        return _even(camera, near, far, step, max_slices, what)
    if not space.is_nearer(closest, near):
        raise LfprocError(f"{what}{near}:{far} starts at {space.text(near)}, but slices of this camera focus only "
                          f"beyond {usable_end(camera)}; give a larger NEAR")
    slices, _, stop = _greedy(camera, near, far, max_gap, integer, max_slices, view_extent)
    if stop == "thin":
        raise LfprocError(f"{what}{near}:{far} reaches within a rounding error of {usable_end(camera)}, where "
                          f"slices are too thin to plan; give a larger NEAR")
    if stop == "limit":
        raise LfprocError(f"{what}{near}:{far} needs more than {max_slices} slices; narrow it")
    return np.array(slices)


def plan_depth_range(camera: Camera, near: float, far: float, *, max_gap: float = 0.0,
                     integer: bool = False, max_slices: int = MAX_SLICES, view_extent=None,
                     what: str = "depth range ") -> SlicePlan:
    """Plan slices for [near, far] like :func:`plan_slices`, covering what can be covered.

    Never refuses a range that is partly coverable: depths nearer than the optics focus (a main lens's
    front focal plane), depths where the slices' DOF shrinks below rounding (next to it), depths left after
    ``max_slices`` slices (the far part is planned first), and the gaps ``max_gap`` or ``integer`` allow
    are returned in :attr:`SlicePlan.uncovered`, each with its reason.

    Raises
    ------
    LfprocError
        For an invalid range, or one that no slice of this camera can focus on at all.
    """
    space = camera.main_optics.object_space
    closest = _check_request(camera, near, far, max_gap, view_extent, what)
    if not space.is_nearer(closest, far):
        raise LfprocError(f"{what}{near}:{far} lies wholly at or before {usable_end(camera)}, where no slice "
                          f"focuses; give a larger FAR")
    start = float(space.farther(near, space.beyond(math.nextafter(closest, -space.toward_optics * math.inf), 1e-12)))
    slices, edge, stop = _greedy(camera, start, far, max_gap, integer, max_slices, view_extent)
    a = np.array(slices)
    uncovered = []
    if slices:
        reason = ("a gap allowed by the integer slices" if integer else f"a gap allowed by max_gap = {max_gap:g}")
        gaps = [space.low_high(lo, hi) for lo, hi in uncovered_depths(camera, a, *space.low_high(edge, far),
                                                                       view_extent)]      # as (near, far)
        uncovered += [(n, f, reason) for n, f in sorted(gaps, key=lambda g: space.toward_optics * g[0])]
    if stop == "limit":
        uncovered.append((start, edge, f"needs more than {max_slices} slices; raise the slice limit to cover it"))
    elif stop == "thin":
        uncovered.append((start, edge, f"slices there are thinner than rounding (DOF -> 0 towards "
                                       f"{usable_end(camera)}); give a larger NEAR"))
    if space.is_nearer(near, start):
        uncovered.append((near, float(space.nearer(start, far)), f"no slice focuses at or nearer than "
                                                                   f"{usable_end(camera)}"))
    return SlicePlan(a, tuple((float(n), float(f), why) for n, f, why in uncovered if space.is_nearer(n, f)))


def uncovered_depths(camera: Camera, a_values, low: float, high: float,
                     view_extent=None) -> list[tuple[float, float]]:
    """Depth intervals inside [low, high] that no slice's DOF interval covers, as numbers low to high.

    Positions are in the camera's object space (:attr:`~lfproc.camera.MainOptics.object_space`): mm from the
    sensor, or for a microscope µm from the native object plane.
    """
    geo = slice_geometry(camera, np.atleast_1d(np.asarray(a_values, dtype=np.float64)), view_extent)
    lows, highs = geo.space.low_high(geo.near, geo.far)
    intervals = sorted(zip(np.atleast_1d(lows), np.atleast_1d(highs)))
    gaps, covered_to = [], low
    for lo, hi in intervals:
        if lo > covered_to and covered_to < high:
            gaps.append((float(covered_to), float(min(lo, high))))
        covered_to = max(covered_to, hi)
    if covered_to < high:
        gaps.append((float(covered_to), float(high)))
    return gaps


def integer_slice_gaps(camera: Camera, a_values, view_extent=None) -> list[tuple[float, float, float]]:
    """Depth gaps that no integer slice covers (the paper's Section 5.2 observation).

    Parameters
    ----------
    a_values : array_like of int
        Slices to inspect, e.g. ``range(0, 6)``.
    view_extent : float, optional
        The extent of the views the slices sum (:func:`slice_geometry`); ``None``: the views the optics fill.

    Returns
    -------
    list of (a, gap_near, gap_far)
        For each consecutive pair (a, a + 1) whose intervals do not touch, the uncovered depths
        between d_(a+1)+ and d_a−, in the camera's object space (the gap's end nearer the optics first).
    """
    a_sorted = np.unique(np.asarray(a_values, dtype=np.float64))
    geo = slice_geometry(camera, a_sorted, view_extent)
    gaps = []
    for k in range(len(a_sorted) - 1):
        if a_sorted[k + 1] != a_sorted[k] + 1:  # only neighbouring integer slices bound a gap between them
            continue
        # slice a + 1 is nearer the optics: its far limit still nearer than slice a's near limit leaves a gap
        nearer_far, farther_near = np.atleast_1d(geo.far)[k + 1], np.atleast_1d(geo.near)[k]
        if geo.space.is_nearer(nearer_far, farther_near):
            gaps.append((float(a_sorted[k]), float(nearer_far), float(farther_near)))
    return gaps


#: a step finer than the depth of field by more than this factor earns a warning (:func:`step_advice`)
FINE_STEP_FACTOR = 10.0


def step_advice(camera: Camera, step: float, near: float, far: float) -> str | None:
    """A warning's text when evenly spaced slices (:func:`plan_slices` with ``step``) are far finer than their
    depth of field.

    Slices a small fraction of their DOF apart show the same thing again (25 µm of DOF sampled every
    0.2 µm repeats each slice a hundred times, issue 32). Returns ``None`` unless ``step`` is more than
    :data:`FINE_STEP_FACTOR` times finer than the thinnest DOF at the range's ends (all views summed, the
    thinnest they can be); the text names a sensible step, half that DOF (neighbours overlap by half,
    so every depth is in focus in two slices).
    """
    space = camera.main_optics.object_space
    ends = slice_geometry(camera, np.atleast_1d(position_parameter(camera, np.array([near, far], dtype=float))))
    dof = float(np.min(ends.dof))
    if not (math.isfinite(dof) and dof > 0 and step * FINE_STEP_FACTOR < dof):
        return None
    return (f"a step of {step:g} {space.symbol} is {dof / step:.0f}x finer than the slices' depth of field "
            f"({dof:.3g} {space.symbol}): neighbouring slices show the same; a step of about {dof / 2:.2g} "
            f"{space.symbol} (half the DOF) samples the depth fully")
