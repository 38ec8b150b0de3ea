"""Where each refocused slice is focused: distance and depth of field (Eqs. 13–31), and the inverse.

Pure, vectorised functions of a :class:`~lfproc.camera.Camera` and the refocus parameter ``a``; no
images. The ray pairs below are followed to the micro lens array; where they meet in object space is
the camera's main optics' business (:attr:`Camera.main_optics`, one interface for a main lens and a
microscope objective, :mod:`lfproc.camera._main_optics`), reported in its unit and from its origin
(``camera.main_optics.object_space``): millimetres from the sensor for a main lens, the closed forms below;
micrometres from the native object plane for a microscope (:mod:`._microscope`).

Closed forms
------------
Write p_m for the micro lens pitch, p_p for the effective pixel pitch (the micro image pitch / m̂),
f_s and f_U for the focal lengths, b_U for the main lens–MLA spacing, ε = b_U − f_U ≥ 0,
δ = p_p / f_s (the slope step between adjacent micro image positions, Eq. 13), κ = 1/d_A (0 for the
telecentric main lens of the 2014 paper, see :mod:`._exit_pupil`) and L = f_s + H1sH2s + b_U + H1UH2U.

Two rays under lenses ΔS = A·p_m apart whose image-side slopes differ by ΔM = δ − C·p_m·κ (per
unit of pixel offset) leave the main lens (Eq. 16) and meet (Eqs. 18–20) at

    x = z − f_U = f_U²·N / (A·p_m + N·ε),     N = δ − C·p_m·κ,

from the front focal plane (Newton's form x·x' = f²), so d = L + f_U + x (Eq. 21).

Central distance (Eqs. 13–21): pixel i under lens j and pixel i + 1 under lens j − a, A = C = a.
Telecentric, d_a = L + f_U + f_U²·δ / (a·p_m + δ·ε): exact at a = 0 (infinite when ε = 0) and
without the cancellation a 2×2 solve of Eq. 20 would suffer up to a = 1e4.

Depth of field (Eqs. 23–31). The extreme pixels merged by Eq. 9 are i = −c under lens j + 2ac and
i = +c under lens j; each pixel's beam fills its micro lens (one lens wide at the MLA) and its pixel
(one view step wide in angle). The slice is sharp where these two beams still overlap. The bounding
border-ray pairs give A = (2ac + s)/(2c + t), C = 2ac/(2c + t) with s = −1 for the far and +1 for
the near limit. The paper (which treats a ≥ 0) always takes t = −s. That is right for a limit in
front of the main lens focus distance (A ≥ 0), where a beam widens as 1 + A lenses; beyond the focus
distance (A < 0) a beam widens as 1 − A and the bounding pair is t = +s (the paper's pair crosses
instead, so its DOF shrinks to zero at a = −1). This module uses the bounding pair on each side
(issue 12, shown with renders in ``docs/exit-pupil.md``); for limits at or in front of the focus
distance, i.e. every a ≥ 1/(2c), the numbers are the paper's.

Views summed (issue 20). The paper's c is the half-extent of the views Eq. 9 averages: the full
micro image, c = (m̂ − 1)/2. When only some views are summed (the light field's view mask, the
views inside the main lens stop, a synthetic aperture) the extreme merged pixels are those of the
outermost summed views, i = ±r, and every formula above holds with r in place of c:
a± = (2ar ± 1)/(2r ∓ 1) (``view_extent`` = r, any real 0 or 1 … c). For a 2-D set of views that is
not the full square, r is the extent of the square set −r … r with the same spread along a lattice
axis (:func:`~lfproc.geometry.summed_view_extent`, derived in :mod:`._aperture`): a point off the slice
blurs into a copy of the summed view set, and how fast a slice loses sharpness is set by that copy's
second moment, not by its outermost view alone (measured on renders in ``docs/aperture.md``). The
full micro image is the square itself, r = c, so the default gives the paper's numbers bit for bit.
With a single view (r = 0) the slice is that view, sharp for |a| ≤ 1 around the focus distance
whatever a is asked; its limits are those of a = ±1.

Each limit is expressed as the central distance of an equivalent parameter
a_eq = A / (1 + (A − C)·p_m·κ/δ) (equal to A when telecentric), so one monotone function d(a)
orders slices and limits alike.

Domain. The rays meet in front of the camera when z > 0: above a_∞ = −δ·ε/(p_m·(1 − κε)), the slice
at infinity, they converge. Between a_0 and a_∞ they diverge: the slice is "beyond infinity" and its
distance is ``inf``. Below a_0 they meet between the main lens and its front focal plane (z < f_U),
a macro regime the paraxial model still describes; distances there are finite and below L + f_U.
With a finite exit pupil, slices far above a = δ·d_A/p_m pass the front focal plane towards the
entrance pupil; where they would meet behind H1U (z ≤ 0) the distance is ``inf``, as PlenoptiSign's
"out of range". Distances are never negative and never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import SENSOR_MM, Camera, ObjectSpace, SlicesInSpace
from ..errors import LfprocError
from ._exit_pupil import pupil_curvature


def _slope_step(camera: Camera) -> float:
    """δ = p_p / f_s with the sample pitch p_p (Eq. 13 for Δu = 1): the micro image pitch over m̂."""
    return camera.sample_pitch_mm / camera.mla_focal_length_mm


def _slope_gap(camera: Camera, spread):
    """N = δ − C·p_m·κ: the difference of the image-side slopes of a ray pair (A, C) of the module docstring
    (exactly δ when telecentric); the pair, A·p_m apart at the MLA, meets A·p_m/N behind it."""
    return _slope_step(camera) - spread * camera.mla_pitch_mm * pupil_curvature(camera)


def _pair_position(camera: Camera, shift, spread):
    """(position, D) of the object point where a ray pair (A, C) meets, through the camera's main optics.

    The position is in the optics' object-space unit (``camera.main_optics.object_space``): for a main lens the
    distance from the sensor, ``inf`` where the rays do not meet in front of it (z ≤ 0 or parallel).
    D = −(N·A_S + A·p_m·C_S) with S the optics' transfer: linear in (A, C) and of the sign of the object
    vergence (for a main lens D = (A·p_m + N·ε)/f_U, the sign of 1/x); it changes sign where the meeting
    point passes through infinity, which an afocal objective (C_S = 0) never does.
    """
    slope_gap, pitch = _slope_gap(camera, spread), camera.mla_pitch_mm
    optics = camera.main_optics
    transfer = optics.transfer()
    vergence = -(slope_gap * transfer.A + shift * pitch * transfer.C)
    return optics.object_position(shift, pitch, slope_gap, camera.mla_path_mm), vergence


def _distance_at(camera: Camera, a) -> np.ndarray:
    """d(a) of the module docstring (A = C = a), vectorised; ``inf`` where the rays do not meet in front."""
    a = np.asarray(a, dtype=np.float64)
    return _pair_position(camera, a, a)[0]


def _equivalent_parameter(camera: Camera, shift, spread):
    """a_eq whose central distance equals the meeting point of a border-ray pair (A, C); A when telecentric."""
    kappa_ratio = camera.mla_pitch_mm * pupil_curvature(camera) / _slope_step(camera)
    return shift / (1.0 + (shift - spread) * kappa_ratio)


def _view_extent(camera: Camera, view_extent) -> float:
    """r of the module docstring: ``view_extent`` checked against the micro image, or c when ``None``."""
    c = camera.center_index
    if view_extent is None:
        return float(c)
    r = float(view_extent)
    if not (r == 0.0 or 1.0 <= r <= c):
        raise LfprocError(f"view_extent {view_extent!r} must be 0 (the central view alone) or from 1 to {c} view "
                          f"steps (the full {camera.m_hat}-px micro image)")
    return r


def _dof_pairs(camera: Camera, a, view_extent=None):
    """((A₋, C₋), (A₊, C₊)): the border-ray pairs bounding slice a on its near and far side.

    ``view_extent`` is r, the half-extent of the summed views in view steps (c when ``None``).
    """
    c = _view_extent(camera, view_extent)
    if camera.center_index == 0:  # m̂ = 1: a single pixel per lens; both borders of the one pixel bound the DOF
        minus_one = np.full_like(a, -1.0)
        return (minus_one, minus_one), (minus_one, minus_one)
    two_ac = 2.0 * a * c
    pairs = []
    for s in (1.0, -1.0):                                # near, far
        # the paper's pair t = -s bounds the beams where the limit is in front of the focus distance
        t = np.where(two_ac + s >= 0.0, -s, s)
        pairs.append(((two_ac + s) / (2.0 * c + t), two_ac / (2.0 * c + t)))
    return pairs[0], pairs[1]


def _dof_parameters(camera: Camera, a, view_extent=None):
    """(a₋, a₊): equivalent central parameters of the near and far DOF limit of slice a."""
    a = np.asarray(a, dtype=np.float64)
    near, far = _dof_pairs(camera, a, view_extent)
    return _equivalent_parameter(camera, *near), _equivalent_parameter(camera, *far)


def require_space(camera: Camera, space: ObjectSpace, what: str) -> None:
    """Refuse ``what``, whose numbers are in ``space`` (e.g. mm from the sensor), for a camera whose main optics
    report positions in another space; one line naming both."""
    actual = camera.main_optics.object_space
    if actual != space:
        raise LfprocError(f"{camera.source or 'camera'}: {what} is in {space.symbol} {space.origin}; this camera's "
                          f"optics ({camera.main_optics.describe()}) place slices in {actual.symbol} {actual.origin}")


def slice_distance_mm(camera: Camera, a) -> np.ndarray | float:
    """Central distance d_a of refocused slice ``a`` from the sensor (Eqs. 13–21; finite d_A: Hahne 2018).

    Parameters
    ----------
    camera : Camera
        Whose optics place slices in mm from the sensor (a main lens).
    a : float or array_like
        Refocus parameter (any real value; positive focuses nearer than a = 0).

    Returns
    -------
    float or ndarray
        Distance in mm; ``inf`` where the chief rays are parallel or diverge.
    """
    require_space(camera, SENSOR_MM, "a slice distance from the sensor")
    d = _distance_at(camera, a)
    return float(d) if d.ndim == 0 else d


@dataclass(frozen=True, eq=False)
class SliceGeometry(SlicesInSpace):
    """Geometry of refocused slices (arrays with the shape of ``a``, or floats for a scalar ``a``).

    One set of fields for any main optics, in the unit and from the origin of ``space`` (the camera's
    :attr:`~lfproc.camera.MainOptics.object_space`): millimetres from the sensor for a main lens (Eqs. 21, 31),
    micrometres from the native object plane, positive towards the objective, for a microscope.

    Attributes
    ----------
    a : refocus parameter
    depth : the slice's position (d_a of Eq. 21, or z)
    near, far : its depth-of-field limits nearer to and farther from the optics (Eq. 31)
    dof : the depth of field |far − near| (Eq. 23; ``inf`` when a limit is at infinity)
    space : ObjectSpace
        Unit, origin and the contract's record keys of the four positions.

    The contract's names read the same numbers: ``distance_mm``, ``near_mm``, ``far_mm``, ``dof_mm`` in
    millimetres from the sensor, ``z_um``, ``z_near_um``, ``z_far_um``, ``dof_um`` in micrometres from the
    native object plane; each is ``None`` where the slices are in the other space.
    """

    a: np.ndarray
    depth: np.ndarray
    near: np.ndarray
    far: np.ndarray
    dof: np.ndarray
    space: ObjectSpace = SENSOR_MM

    def records(self) -> list[dict]:
        """One dict per slice with the contract's JSON keys (``space.keys``); infinity as ``math.inf``.

        A camera's slices: ``a, distance_mm, near_mm, far_mm, dof_mm``; a microscope's: ``a, z_um,
        z_near_um, z_far_um, dof_um``.
        """
        cols = [np.atleast_1d(np.asarray(x, dtype=np.float64)) for x in
                (self.a, self.depth, self.near, self.far, self.dof)]
        keys = ("a",) + tuple(self.space.keys)
        return [dict(zip(keys, map(float, row))) for row in zip(*cols)]


def slice_geometry(camera: Camera, a, view_extent=None) -> SliceGeometry:
    """Distance and depth of field of refocused slices (Eqs. 13–31).

    Parameters
    ----------
    camera : Camera
    a : float or array_like
        Refocus parameters.
    view_extent : float, optional
        r, the half-extent in view steps of the views the slices average (the largest offset along a
        lattice axis, :func:`~lfproc.geometry.summed_view_extent`); ``None`` (default) is the full micro
        image, c = (m̂ − 1)/2, the paper's DOF. Fewer views summed give a deeper DOF (module docstring).

    Returns
    -------
    SliceGeometry
        ``near_mm <= distance_mm <= far_mm`` always holds; limits are ``inf`` where the bounding
        rays do not meet in front of the camera. Limits beyond the focus distance use the border
        rays that bound the beams there (see the module docstring), so the DOF never collapses.
        For a microscope camera the ``_um`` fields instead (:func:`~._microscope.microscope_slices`).
    """
    optics = camera.main_optics
    space = optics.object_space
    a_arr = np.asarray(a, dtype=np.float64)
    if view_extent is None:
        view_extent = _lit_view_extent(camera)
    d, d_sign = _pair_position(camera, a_arr, a_arr)
    near_pair, far_pair = _dof_pairs(camera, a_arr, view_extent)
    limit1, sign1 = _pair_position(camera, *near_pair)
    limit2, sign2 = _pair_position(camera, *far_pair)
    near = space.nearer(space.nearer(limit1, limit2), d)     # nearer the optics: less distance, more z
    far = space.farther(space.farther(limit1, limit2), d)
    # D is linear along the border rays' path from the central pair to each limit (up to a positive
    # factor): a sign change on either path means the DOF passes through infinity
    centre_in_front = d_sign > 0
    crosses = (centre_in_front != (sign1 > 0)) | (centre_in_front != (sign2 > 0))
    if camera.center_index == 0:   # one pixel per lens: both limits are the same pair, not a path from the centre
        crosses = np.zeros_like(crosses)
    far = np.where(crosses, np.inf, far)
    in_front = np.minimum(np.where(sign1 > 0, limit1, np.inf), np.where(sign2 > 0, limit2, np.inf))
    near = np.where(crosses, np.minimum(in_front, d), near)
    half_wave = 0.5 * optics.wave_depth_of_field()        # a microscope's wave term, split evenly (0 for a lens)
    if half_wave:
        near, far = near + space.toward_optics * half_wave, far - space.toward_optics * half_wave
    with np.errstate(invalid="ignore"):
        dof = np.where(np.isinf(far) | np.isinf(near), np.inf, np.abs(far - near))
    if a_arr.ndim == 0:
        return SliceGeometry(float(a_arr), float(d), float(near), float(far), float(dof), space)
    return SliceGeometry(a_arr, d, near, far, dof, space)


def _lit_view_extent(camera: Camera) -> float:
    """r of the DOF when no views are named: the views the main optics fill (the full micro image, c, for a
    main lens: the paper's DOF; the views inside the NA for an objective, ``MainOptics.lit_view_extent``)."""
    return camera.main_optics.lit_view_extent(camera.sample_pitch_mm, camera.mla_focal_length_mm,
                                              camera.center_index)


def infinity_parameter(camera: Camera) -> float:
    """a_∞: the refocus parameter of the slice focused at infinity (−δ·ε/(p_m·(1 − κε)) of a main lens, 0 when
    b_U = f_U), the far end of the optics' usable range.

    Raises
    ------
    LfprocError
        For optics with no slice at infinity (an afocal objective: every a is a finite depth).
    """
    usable = camera.main_optics.usable_range(camera)
    if not (np.isfinite(usable.low) and np.isinf(usable.low_position)):
        raise LfprocError(f"{camera.source or 'camera'}: this camera's optics ({camera.main_optics.describe()}) have "
                          f"no slice at infinity: every a focuses at a finite depth")
    return usable.low


def refocus_parameter(camera: Camera, distance_mm) -> np.ndarray | float:
    """The ``a`` whose slice is centred at ``distance_mm`` from the sensor (inverse of Eq. 21).

    a = δ·(f_U²/x − ε) / (p_m·(1 − κε + κ·f_U²/x)) with x = d − L − f_U, the distance from the front
    focal plane (κ = 0 when telecentric; :meth:`lfproc.camera.MainLens.refocus_parameter`).

    Raises
    ------
    LfprocError
        For a distance at or behind the main lens (d ≤ L), or NaN; for optics whose positions are not mm
        from the sensor (:func:`position_parameter` takes any optics' own).

    Parameters
    ----------
    camera : Camera
        With a main lens (positions in mm from the sensor).
    distance_mm : float or array_like
        Distances from the sensor, mm.

    Returns
    -------
    float or ndarray
        ``a`` of the same shape.
    """
    require_space(camera, SENSOR_MM, "a distance in mm (`distance_mm=`)")
    return camera.main_optics.refocus_parameter(camera, distance_mm)


def position_parameter(camera: Camera, position) -> np.ndarray | float:
    """The ``a`` whose slice is centred at ``position``, in the optics' own object space (mm from the sensor,
    µm from a native object plane, …): the inverse of the central ray pair's position (Eqs. 13–21).

    Raises
    ------
    LfprocError
        For a position no slice of these optics can focus on, in the optics' own words.

    Parameters
    ----------
    camera : Camera
    position : float or array_like
        Positions in ``camera.main_optics.object_space`` (its unit).

    Returns
    -------
    float or ndarray
        ``a`` of the same shape.
    """
    return camera.main_optics.refocus_parameter(camera, position)
