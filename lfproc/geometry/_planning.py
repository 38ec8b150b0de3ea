"""Slice planning: the fewest refocus parameters whose DOF intervals cover a depth range, and what they miss."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ._exit_pupil import pupil_curvature
from ._slices import _slope_step, _view_extent, refocus_parameter, slice_geometry

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
    uncovered : tuple of (near_mm, far_mm, reason)
        Depth intervals of the request that no planned slice's DOF covers, nearest last, each with
        a one-line reason (a gap allowed by ``max_gap_mm`` or ``integer``, the slice limit, or the
        part of the range no slice can focus on).
    """

    a: np.ndarray
    uncovered: tuple

    @property
    def complete(self) -> bool:
        """True when every depth of the request lies in some slice's DOF."""
        return not self.uncovered


def _slice_for_far_limit(camera: Camera, far_mm: float, view_extent=None) -> float:
    """The ``a`` whose far DOF limit equals ``far_mm``: inverts a₊ of :func:`slice_geometry` (c → r, view_extent)."""
    c = _view_extent(camera, view_extent)
    a_limit = refocus_parameter(camera, far_mm)
    ratio = camera.mla_pitch_mm * pupil_curvature(camera) / _slope_step(camera)
    if a_limit >= 0:   # limit at or in front of the focus distance: A = (2ac − 1)/(2c + 1)
        a = (a_limit * (1.0 - ratio / (2.0 * c + 1.0)) * (2.0 * c + 1.0) + 1.0) / (2.0 * c)
    else:              # beyond it the bounding pair is A = (2ac − 1)/(2c − 1)
        a = (a_limit * (1.0 - ratio / (2.0 * c - 1.0)) * (2.0 * c - 1.0) + 1.0) / (2.0 * c)
    # Near infinity a₊ cancels digits, so the far limit of that a can fall short of far_mm (or stay
    # finite for far_mm = inf). Lower a by doubling steps from the rounding of a₊ until it reaches:
    # the far limit never increases with a, so this ends, overshooting by < 2 steps.
    step = 2.0 ** -52 * (abs(a) + 1.0 / (2.0 * c))
    for _ in range(2000):
        if slice_geometry(camera, a, view_extent).far_mm >= far_mm:
            break
        a -= step
        step *= 2.0
    return a


def _check_request(camera: Camera, near_mm: float, far_mm: float, max_gap_mm: float, view_extent=None) -> float:
    if camera.center_index == 0:
        raise LfprocError("depth-range planning needs micro images of 3 px or more (micro_image_px >= 3)")
    if _view_extent(camera, view_extent) == 0:
        raise LfprocError("depth-range planning needs more than the central view summed (one view does not "
                          "refocus); give a wider aperture=")
    if not (near_mm > 0 and far_mm >= near_mm) or math.isnan(far_mm):
        raise LfprocError(f"depth range {near_mm}:{far_mm} mm is not a valid range; give NEAR:FAR with 0 < NEAR <= FAR")
    if not (max_gap_mm >= 0 and math.isfinite(max_gap_mm)):
        raise LfprocError(f"the largest allowed DOF gap must be a finite number of mm >= 0, got {max_gap_mm}")
    return camera.sensor_to_main_lens_mm + camera.main_focal_length_mm


def _greedy(camera, near_mm, far_mm, max_gap_mm, integer, max_slices, view_extent=None):
    """The greedy plan of :func:`plan_slices`; returns (slices, edge, why it stopped early or None)."""
    slices: list[float] = []
    edge = far_mm                   # everything beyond the edge is covered (or an allowed gap)
    target = far_mm * (1.0 + 1e-9)  # every target a hair beyond, so rounding never leaves a sliver uncovered
    while True:
        a = _slice_for_far_limit(camera, target, view_extent)
        if integer:  # the largest integer whose far limit still reaches the target (far decreases with a)
            a = float(math.floor(a + 1e-9))
            if slices and a <= slices[-1]:
                a = slices[-1] + 1.0
            if float(slice_geometry(camera, a, view_extent).near_mm) >= edge:
                a += 1.0  # its interval lies wholly beyond the edge: the next integer makes progress
        reached = float(slice_geometry(camera, a, view_extent).near_mm)
        if reached > edge and not integer:  # the DOF here is narrower than the 1e-9 overlap: no progress possible
            return slices, edge, "thin"
        slices.append(a)
        edge = min(edge, reached)
        if edge <= near_mm:
            return slices, edge, None
        if len(slices) >= max_slices:
            return slices, edge, "limit"
        target = max(edge - max_gap_mm, near_mm) * (1.0 + 1e-9)


def plan_slices(camera: Camera, near_mm: float, far_mm: float, *, max_gap_mm: float = 0.0, integer: bool = False,
                max_slices: int = MAX_SLICES, view_extent=None) -> np.ndarray:
    """The fewest refocus parameters whose [near, far] DOF intervals together cover [near_mm, far_mm].

    Greedy from the far end, which is optimal for intervals whose both ends decrease with ``a``:
    each slice is the one whose far limit sits exactly on the nearest point not yet covered, so its
    near limit reaches as close as any slice covering that point can. Neighbouring intervals touch
    (with a 1e-9 relative overlap against rounding), so no depth in the range is left out of focus.

    Two ways to compute less, when the scene allows:

    * ``max_gap_mm`` > 0 tolerates uncovered depths up to that size *between* slices (never at the
      ends of the range): the next slice's far limit may sit that much nearer, so fewer slices.
    * ``integer=True`` uses integer ``a`` only — pure gathers, no interpolation, the cheapest slices —
      and leaves the gaps between integer slices that the paper points out (Section 5.2). Where even
      the next integer cannot keep a gap within ``max_gap_mm`` it is taken anyway; check the result
      with :func:`uncovered_depths`.

    This strict form refuses a range it cannot cover whole; :func:`plan_depth_range` plans what can
    be covered and names the rest.

    Parameters
    ----------
    camera : Camera
        Needs m̂ ≥ 3 (a single-pixel micro image cannot refocus).
    near_mm, far_mm : float
        The depth range from the sensor; ``far_mm`` may be ``inf``.
    max_gap_mm : float
        Largest uncovered depth interval allowed between slices.
    integer : bool
        Plan integer refocus parameters only.
    max_slices : int
        Guard against ranges that would need absurdly many slices (default :data:`MAX_SLICES`).
    view_extent : int, optional
        Half-extent of the views the slices will average (:func:`slice_geometry`); the full micro image
        when ``None``.

    Returns
    -------
    ndarray of float
        Refocus parameters, far slice first (increasing ``a``).
    """
    closest = _check_request(camera, near_mm, far_mm, max_gap_mm, view_extent)
    if near_mm <= closest:
        raise LfprocError(f"depth range starts at {near_mm} mm, but slices of this camera focus only beyond "
                          f"{closest:.3f} mm from the sensor; give a larger NEAR")
    slices, _, stop = _greedy(camera, near_mm, far_mm, max_gap_mm, integer, max_slices, view_extent)
    if stop == "thin":
        raise LfprocError(f"depth range {near_mm}:{far_mm} mm reaches within a rounding error of the nearest "
                          f"slice ({closest:.3f} mm), where slices are too thin to plan; give a larger NEAR")
    if stop == "limit":
        raise LfprocError(f"depth range {near_mm}:{far_mm} mm needs more than {max_slices} slices; narrow it")
    return np.array(slices)


def plan_depth_range(camera: Camera, near_mm: float, far_mm: float, *, max_gap_mm: float = 0.0,
                     integer: bool = False, max_slices: int = MAX_SLICES, view_extent=None) -> SlicePlan:
    """Plan slices for [near_mm, far_mm] like :func:`plan_slices`, covering what can be covered.

    Never refuses a range that is partly coverable: depths nearer than the front focal plane (no
    slice focuses there), depths where the slices' DOF shrinks below rounding (next to the front
    focal plane), depths left after ``max_slices`` slices (the far part is planned first), and the
    gaps ``max_gap_mm`` or ``integer`` allow are returned in :attr:`SlicePlan.uncovered`, each with
    its reason.

    Raises
    ------
    LfprocError
        For an invalid range, or one that no slice of this camera can focus on at all.
    """
    closest = _check_request(camera, near_mm, far_mm, max_gap_mm, view_extent)
    if far_mm <= closest:
        raise LfprocError(f"depth range {near_mm}:{far_mm} mm lies wholly at or before the front focal plane "
                          f"({closest:.3f} mm from the sensor), where no slice focuses; give a larger FAR")
    start = max(near_mm, math.nextafter(closest, math.inf) * (1.0 + 1e-12))
    slices, edge, stop = _greedy(camera, start, far_mm, max_gap_mm, integer, max_slices, view_extent)
    a = np.array(slices)
    uncovered = []
    if slices:
        reason = ("a gap allowed by the integer slices" if integer else
                  f"a gap allowed by max_gap_mm = {max_gap_mm:g}")
        gaps = uncovered_depths(camera, a, edge, far_mm, view_extent)
        uncovered += [(lo, hi, reason) for lo, hi in reversed(gaps)]
    if stop == "limit":
        uncovered.append((start, edge, f"needs more than {max_slices} slices; raise the slice limit to cover it"))
    elif stop == "thin":
        uncovered.append((start, edge, "slices there are thinner than rounding (DOF -> 0 towards the front "
                                       "focal plane); give a larger NEAR"))
    if near_mm < start:
        uncovered.append((near_mm, min(start, far_mm), f"no slice focuses at or before the front focal plane "
                                                       f"({closest:.3f} mm from the sensor)"))
    return SlicePlan(a, tuple((float(lo), float(hi), why) for lo, hi, why in uncovered if hi > lo))


def uncovered_depths(camera: Camera, a_values, near_mm: float, far_mm: float,
                     view_extent=None) -> list[tuple[float, float]]:
    """Depth intervals inside [near_mm, far_mm] that no slice's [near, far] DOF interval covers.

    Positions are in the camera's object space (:attr:`~lfproc.camera.Camera.object_space`): mm from the
    sensor, or for a microscope µm from the native object plane, the range then given low to high.
    """
    geo = slice_geometry(camera, np.atleast_1d(np.asarray(a_values, dtype=np.float64)), view_extent)
    low, high = _low_high(geo)
    intervals = sorted(zip(np.atleast_1d(low), np.atleast_1d(high)))
    gaps, covered_to = [], near_mm
    for lo, hi in intervals:
        if lo > covered_to and covered_to < far_mm:
            gaps.append((float(covered_to), float(min(lo, far_mm))))
        covered_to = max(covered_to, hi)
    if covered_to < far_mm:
        gaps.append((float(covered_to), float(far_mm)))
    return gaps


def integer_slice_gaps(camera: Camera, a_values, view_extent=None) -> list[tuple[float, float, float]]:
    """Depth gaps that no integer slice covers (the paper's Section 5.2 observation).

    Parameters
    ----------
    a_values : array_like of int
        Slices to inspect, e.g. ``range(0, 6)``.
    view_extent : float, optional
        The extent of the views the slices sum (:func:`slice_geometry`); ``None``: the full micro image.

    Returns
    -------
    list of (a, gap_near_mm, gap_far_mm)
        For each consecutive pair (a, a + 1) whose intervals do not touch, the uncovered depths
        between d_(a+1)+ and d_a−, in the camera's object space (for a microscope µm, the gap's
        end nearer the objective first).
    """
    a_sorted = np.unique(np.asarray(a_values, dtype=np.float64))
    geo = slice_geometry(camera, a_sorted, view_extent)
    # slice a + 1 is nearer the optics: a smaller distance from the sensor, a larger signed depth
    apart = np.less if geo.space.from_sensor else np.greater
    gaps = []
    for k in range(len(a_sorted) - 1):
        if a_sorted[k + 1] != a_sorted[k] + 1:  # only neighbouring integer slices bound a gap between them
            continue
        nearer_far, farther_near = np.atleast_1d(geo.far)[k + 1], np.atleast_1d(geo.near)[k]
        if apart(nearer_far, farther_near):
            gaps.append((float(a_sorted[k]), float(nearer_far), float(farther_near)))
    return gaps


def _low_high(geo):
    """(low, high): each slice's DOF interval as numbers low to high (near first from the sensor, far first
    for signed depths, where the limit nearer the optics is the larger number)."""
    return (geo.near, geo.far) if geo.space.from_sensor else (geo.far, geo.near)
