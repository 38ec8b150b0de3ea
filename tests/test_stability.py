"""Stability suite (issue 7, item 4): the numerical extremes of geometry, refocusing, decoding and LightField.

Every check compares against an independent reference:

* geometry: the paper's chief- and border-ray trace (Eqs. 13-20, 24-31) evaluated in *exact* rational
  arithmetic (``fractions.Fraction``) on the very float inputs the module sees, so any loss of digits in
  the module's closed forms shows up; error bounds are first-order propagations of the unit roundoff
  ``U`` = 2**-53 (derived next to each bound);
* refocus: a plain-numpy implementation of the contract's centred Eq. 9 (dense per-axis interpolation
  matrices from the textbook kernels), exact integer means for uint16 data;
* decode: plain reshapes of aligned sensors and explicit per-sample ratios;
* LightField: bit-exact round trips.

Parameter ranges follow the issue: a from 1e-12 to 1e4, b_U - f_U from 1e-12 mm, pitches from 1 um to
1 mm, focal lengths from 0.1 mm to 1 m, m-hat from 1 to 99, one-lens-wide light fields, uint16 at 65535,
NaN/inf pixels, empty a lists. Warnings of the RuntimeWarning family (overflow, invalid casts) fail
every test, and geometry runs under ``np.errstate(all="raise")`` (underflow excepted).
"""

import contextlib
import importlib
import math
import os
from fractions import Fraction as Fr

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from focus import focused
from lfproc import Camera, LensGrid, LfprocError, LightField
from test_refocus import _bspline, _spline_filter
from lfproc import geometry as g
from lfproc.decode import decode, make_decoder
from lfproc.camera import MainLens

rf = importlib.import_module("lfproc.refocusing")   # the module (``lfproc.refocus`` may be bound to the function)

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

U = 2.0 ** -53          # unit roundoff of float64
U32 = 2.0 ** -24        # unit roundoff of float32
INTERPOLATIONS = ("nearest", "linear", "cubic", "cubic-spline")
#: multiply every property test's example count, for a deeper run: LFPROC_STABILITY_SCALE=20 pytest ...
EXAMPLES_SCALE = float(os.environ.get("LFPROC_STABILITY_SCALE", "1"))


def fast(examples):
    """Hypothesis settings: bounded examples, no per-example deadline (numba compiles on first use)."""
    return settings(max_examples=max(1, int(examples * EXAMPLES_SCALE)), deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


@contextlib.contextmanager
def strict_floats():
    """Overflow, invalid operations and division by zero raise (gradual underflow to subnormals is harmless)."""
    with np.errstate(all="raise", under="ignore"):
        yield


def one_line_error(excinfo, *words):
    message = str(excinfo.value)
    assert "\n" not in message and message
    for word in words:
        assert word in message, (word, message)


# ============================================================================ geometry
def log_uniform(lo, hi):
    """Floats spread evenly in log10 between lo and hi, both ends included."""
    return st.one_of(st.sampled_from([lo, hi]),
                     st.floats(math.log10(lo), math.log10(hi)).map(lambda e: float(10.0 ** e)))


@st.composite
def cameras(draw, min_ratio=1.0):
    """Cameras over the issue's ranges: pitches 1 um-1 mm, focal lengths 0.1 mm-1 m, b_U - f_U in {0} U [1e-12, 1e3]."""
    p1, p2 = draw(log_uniform(1e-3, 1.0)), draw(log_uniform(1e-3, 1.0))
    pixel, lens = min(p1, p2), max(p1, p2)
    assume(lens / pixel >= min_ratio)
    fs, fu = draw(log_uniform(0.1, 1000.0)), draw(log_uniform(0.1, 1000.0))
    eps = draw(st.one_of(st.just(0.0), log_uniform(1e-12, 1e3)))
    gap_s = fs * draw(st.one_of(st.just(0.0), st.floats(-0.5, 0.5)))
    gap_u = fu * draw(st.one_of(st.just(0.0), st.floats(-0.5, 0.5)))
    return Camera(pixel, lens, fs, MainLens(fu, fu + eps, principal_plane_gap_mm=gap_u), mla_principal_plane_gap_mm=gap_s)


a_values = st.one_of(st.just(0.0), log_uniform(1e-12, 1e-3), log_uniform(1e-3, 1e4), st.integers(0, 50).map(float))


class Exact:
    """The paper's ray model in exact rational arithmetic on the camera's float parameters.

    ``trace`` follows Eqs. 24-29 step by step (Eqs. 13-19 for border offsets 0) for two rays, pixel
    offset i under lens j with (pixel border, lens border) offsets, and solves Eq. 20/30 for z.
    """

    def __init__(self, cam):
        self.cam = cam
        self.pm = Fr(cam.mla_pitch_mm)
        self.pp = self.pm / cam.m_hat                     # effective pixel pitch, exactly p_m / m-hat
        self.fs, self.fu, self.bu = Fr(cam.mla_focal_length_mm), Fr(cam.main_optics.focal_length_mm), Fr(cam.main_optics.image_distance_mm)
        self.L = self.fs + Fr(cam.mla_principal_plane_gap_mm) + self.bu + Fr(cam.main_optics.principal_plane_gap_mm)
        self.L_terms = (abs(cam.mla_focal_length_mm) + abs(cam.mla_principal_plane_gap_mm)
                        + cam.main_optics.image_distance_mm + abs(cam.main_optics.principal_plane_gap_mm))
        self.delta = self.pp / self.fs
        self.eps = self.bu - self.fu
        self.c = cam.center_index

    def trace(self, ray1, ray2):
        """z (from H1U) where two rays ((i, j, pixel border, lens border), ...) meet; None when parallel."""
        lines = []
        for i, j, pb, lb in (ray1, ray2):
            m = (-i + Fr(pb)) * self.pp / self.fs                  # Eq. 24 (Eq. 13 for pb = 0), Δu = -i
            s = Fr(j) * self.pm + self.pm / 2 + Fr(lb) * self.pm   # Eq. 25 (Eq. 14 for lb = 0)
            u = m * self.bu + s                                    # Eq. 26
            q = (m * self.fu - u) / self.fu                        # Eqs. 27-28
            lines.append((q, u))
        (q1, u1), (q2, u2) = lines
        return None if q1 == q2 else (u2 - u1) / (q1 - q2)         # Eq. 29: q1 z + u1 = q2 z + u2

    def central_z(self, a):
        """Eq. 20 for neighbouring views merged by Eq. 9: pixel 0 under lens 0, pixel 1 under lens -a."""
        return self.trace((0, 0, 0, 0), (1, -Fr(a), 0, 0))

    def border_z(self, a, inner):
        """Eq. 30: extreme pixels i = -c under lens 2ac and i = +c under lens 0, inner or outer border rays.

        Issue 12: a limit beyond the focus distance (its A = (2ac -/+ 1)/... below 0) is bounded by the
        pair with the pixel borders swapped (the beams widen as 1 - A there); see lfproc.geometry._slices.
        """
        c, j = self.c, 2 * Fr(a) * self.c
        h = Fr(1, 2)
        if inner:
            pb = -h if j + 1 >= 0 else h
            return self.trace((-c, j, pb, h), (c, 0, -pb, -h))
        pb = h if j - 1 >= 0 else -h
        return self.trace((-c, j, pb, -h), (c, 0, -pb, h))

    def border_parameter(self, a, inner):
        """A of the border pair :meth:`border_z` traces: (2ac ± 1)/(2c ∓ 1) in front of the focus, else (2c ± 1)."""
        c, j = self.c, 2 * Fr(a) * self.c
        if inner:
            return (j + 1) / (2 * c - 1) if j + 1 >= 0 else (j + 1) / (2 * c + 1)
        return (j - 1) / (2 * c + 1) if j - 1 >= 0 else (j - 1) / (2 * c - 1)

    def distance(self, z):
        """Eq. 21/31 for a meeting point z beyond the front focal plane; inf when there is none."""
        return math.inf if z is None or z <= self.fu else self.L + z

    def parameter_slope(self, alpha):
        """D(alpha) = alpha·p_m + δ·ε: the denominator of the Newton form d = L + f_U + f_U²δ/D."""
        return Fr(alpha) * self.pm + self.delta * self.eps

    def error_bound(self, alpha, alpha_error):
        """|float d(alpha) - exact d(alpha)| for the module's Newton form, to first order in U.

        D = alpha·p_m + δ·ε sums non-negative terms (2 roundings of its own, 2 in δ, 1 in ε), plus
        p_m times the error of a computed alpha; X = f_U²·δ/D adds 4 more roundings; the additions
        L + f_U + X add one ulp of each partial sum, and L itself carries 3 roundings of its terms.
        A factor 2 covers second-order terms.
        """
        D = self.parameter_slope(alpha)
        if D == 0:
            return 0.0                      # parallel chief rays: d is exactly inf
        x = float(self.fu ** 2 * self.delta / D)
        magnitude = float(abs(Fr(alpha)) * self.pm + self.delta * self.eps)
        rel_D = (6 * U * magnitude + float(self.pm) * alpha_error) / float(D)
        return 2.0 * (x * (8 * U + rel_D) + 6 * U * (self.L_terms + float(self.fu) + x))


def assert_within(actual, exact, bound, what):
    if math.isinf(exact):
        assert math.isinf(actual), (what, actual)
        return
    assert math.isfinite(actual), (what, actual, float(exact))
    error = abs(Fr(actual) - exact)
    assert error <= Fr(bound), (what, actual, float(exact), float(error), bound)


@fast(300)
@given(cam=cameras(), a=a_values)
@example(cam=Camera(1e-3, 1.0, 0.1, MainLens(1000.0, 1000.0 + 1e-12)), a=1e-12)
@example(cam=Camera(1.0, 1.0, 1000.0, MainLens(0.1, 0.1)), a=1e4)
@example(cam=Camera(0.01, 0.25, 2.749, MainLens(99.5145, 99.5145)), a=0.0)
def test_slice_geometry_is_exact_to_rounding_over_the_whole_range(cam, a):
    """d, near and far against the exact ray trace: no NaN, no negatives, order, and only rounding errors."""
    with strict_floats():
        geo = g.slice_geometry(cam, a)
    values = (geo.distance_mm, geo.near_mm, geo.far_mm, geo.dof_mm)
    assert not any(math.isnan(v) for v in values) and min(values[:3]) > 0 and geo.dof_mm >= 0
    assert geo.near_mm <= geo.distance_mm <= geo.far_mm
    assert geo.dof_mm == (math.inf if math.isinf(geo.far_mm) else geo.far_mm - geo.near_mm)

    ex = Exact(cam)
    assert_within(geo.distance_mm, ex.distance(ex.central_z(a)), ex.error_bound(a, 0.0), "d")
    if ex.c == 0:
        return   # a one-pixel micro image has no extreme pixel pair: Eq. 30 does not apply
    c = ex.c
    a_minus, a_plus = ex.border_parameter(a, inner=True), ex.border_parameter(a, inner=False)
    # the module computes a± = (2ac ± 1)/(2c ∓ 1) in floats: 3 roundings of magnitude (2|a|c + 1)/(2c - 1)
    alpha_error = 4 * U * (2 * a * c + 1) / (2 * c - 1)
    assert_within(geo.near_mm, ex.distance(ex.border_z(a, inner=True)), ex.error_bound(a_minus, alpha_error), "near")
    # far is infinite iff the outer rays do not meet beyond the focal plane (D(a+) <= 0); skip the
    # knife edge where the rounding of a+ alone can decide that
    slack = float(ex.pm) * alpha_error + 8 * U * float(abs(a_plus) * ex.pm + ex.delta * ex.eps)
    assume(abs(float(ex.parameter_slope(a_plus))) > 100 * slack)
    assert_within(geo.far_mm, ex.distance(ex.border_z(a, inner=False)), ex.error_bound(a_plus, alpha_error), "far")


@fast(300)
@given(cam=cameras(), a=a_values)
@example(cam=Camera(1e-3, 1.0, 0.1, MainLens(1000.0, 1000.0 + 1e-12)), a=1e-12)
@example(cam=Camera(1e-3, 1e-3, 1000.0, MainLens(0.1, 0.1 + 1e-12)), a=1e4)
def test_inverse_round_trip_within_the_propagated_bound(cam, a):
    """refocus_parameter(slice_distance(a)) == a up to the propagated rounding.

    With x = d - L - f_U (Newton's object distance) the inverse is a = δ(f_U²/x - ε)/p_m, so
    da/dd = -(a - a_∞)/x: an error E in d becomes (a - a_∞)·E/x in a. E is the forward error (bounded
    above) plus the subtraction d - L - f_U, at most 4 ulps of |d| + L + f_U; the remaining operations
    add 8 roundings relative to a - a_∞ = a + |a_∞|. Factor 2 as above.
    """
    with strict_floats():
        d = g.slice_distance_mm(cam, a)
        back = g.refocus_parameter(cam, d)
        a_inf = g.infinity_parameter(cam)
    assert math.isfinite(back) and not math.isnan(d)
    if math.isinf(d):                       # a = 0 with b_U = f_U: the slice at infinity, and back
        assert a == 0.0 and cam.main_optics.image_distance_mm == cam.main_optics.focal_length_mm and back == a_inf == 0.0
        return
    ex = Exact(cam)
    x = float(ex.central_z(a) - ex.fu)
    forward = ex.error_bound(a, 0.0)
    bound = 2.0 * (a + abs(a_inf)) * ((forward + 4 * U * (d + ex.L_terms + cam.main_optics.focal_length_mm)) / x + 8 * U)
    assert abs(back - a) <= bound, (back, a, bound)


def test_round_trip_bound_is_not_vacuous():
    """The bound above stays small for the paper's camera: ~1e-13 of a where x is large, and no more than
    the unavoidable u·d/x conditioning (tens of ulps) at a = 1e4, where the slice is 0.014 mm from the
    front focal plane and d ≈ 200 mm carries only ~12 digits of x."""
    cam = Camera(0.01, 0.25, 2.749, MainLens(99.5145, 99.5145 + 10.0, principal_plane_gap_mm=-33.184), mla_principal_plane_gap_mm=0.374)
    ex = Exact(cam)
    for a, relative in ((1e-12, 1e-13), (1e-6, 1e-13), (1.0, 1e-13), (1e4, 1e-10)):
        d = g.slice_distance_mm(cam, a)
        x = float(ex.central_z(a) - ex.fu)
        scale = a + abs(g.infinity_parameter(cam))
        bound = 2.0 * scale * ((ex.error_bound(a, 0.0) + 4 * U * (d + ex.L_terms + 99.5145)) / x + 8 * U)
        assert bound <= relative * scale and bound <= 100 * U * scale * (d / x + 1)
        assert abs(g.refocus_parameter(cam, d) - a) <= bound


@fast(200)
@given(cam=cameras(), a1=a_values, a2=a_values)
def test_distance_and_limits_never_increase_with_a(cam, a1, a2):
    """Monotone in floating point too: every step of the Newton form is a monotone IEEE operation."""
    lo, hi = sorted((a1, a2))
    with strict_floats():
        geo = g.slice_geometry(cam, np.array([lo, hi]))
    assert geo.distance_mm[0] >= geo.distance_mm[1]
    assert geo.near_mm[0] >= geo.near_mm[1]
    assert geo.far_mm[0] >= geo.far_mm[1]


@fast(150)
@given(cam=cameras(), a=st.floats(-1e4, 1e4))
def test_every_real_a_gives_ordered_non_negative_limits(cam, a):
    """Beyond infinity (a_0 < a < a_∞) and the macro regime (a < a_0) included: no NaN, nothing negative."""
    grid = np.array([a, g.infinity_parameter(cam), np.nextafter(g.infinity_parameter(cam), -1.0), -1.0, 0.0])
    with strict_floats():
        geo = g.slice_geometry(cam, grid)
    for arr in (geo.distance_mm, geo.near_mm, geo.far_mm, geo.dof_mm):
        assert not np.isnan(arr).any() and (arr >= 0).all()
    assert (geo.near_mm <= geo.distance_mm).all() and (geo.distance_mm <= geo.far_mm).all()
    # a_∞ is the slice at infinity; its float value leaves |D| <= 4U·δε, so d is inf or >= f_U²/(8Uε)
    eps = cam.main_optics.image_distance_mm - cam.main_optics.focal_length_mm
    assert math.isinf(geo.distance_mm[1]) or geo.distance_mm[1] >= cam.main_optics.focal_length_mm ** 2 / (8 * U * eps)


@fast(100)
@given(fu=log_uniform(0.1, 1000.0), scale=log_uniform(1e-12, 1e-2))
def test_b_u_approaching_f_u_from_above_is_continuous(fu, scale):
    """ε = b_U - f_U → 0: a_∞ → 0, d(0) = L + f_U + f_U²/ε, tilts → 0 with the sign of F_i, and
    d(a > 0) → its ε = 0 value."""
    base = Camera(1e-3 * 7, 0.25, 2.0, MainLens(fu, fu))
    eps_target = scale * fu
    cam = Camera(base.pixel_pitch_mm, 0.25, 2.0, MainLens(fu, fu + eps_target))
    eps = Fr(cam.main_optics.image_distance_mm) - Fr(fu)                      # the ε the float b_U actually carries
    assume(eps > 0)
    ex = Exact(cam)
    with strict_floats():
        d0 = g.slice_distance_mm(cam, 0.0)
        a_inf = g.infinity_parameter(cam)
        tilts = g.view_tilts_deg(cam)
        pos = g.view_positions_mm(cam)
        d1, d1_flat = g.slice_distance_mm(cam, 1.0), g.slice_distance_mm(base, 1.0)
    assert_within(d0, ex.L + ex.fu + ex.fu ** 2 / eps, ex.error_bound(0.0, 0.0), "d(0)")
    assert a_inf < 0 and abs(Fr(a_inf) + ex.delta * eps / ex.pm) <= 4 * U * abs(a_inf)
    assert np.all(np.isfinite(tilts)) and np.all(np.sign(tilts) == np.sign(pos))
    assert np.all(np.abs(tilts) <= np.degrees(np.abs(pos) * float(eps) / fu ** 2) * (1 + 1e-12))
    # continuity: d(1) moves by f_U²δ·δε/(p_m + δε)/p_m ≈ X·δε/p_m between ε = 0 and ε
    x1 = d1_flat - base.main_optics.sensor_path_mm(base.mla_path_mm) - fu
    # (plus ε itself, by which L moves, plus a few ulps of d from each evaluation)
    assert abs(d1 - d1_flat) <= x1 * float(ex.delta * eps / ex.pm) + float(eps) + 16 * U * d1


@fast(100)
@given(cam=cameras())
def test_views_at_the_extremes(cam):
    """Eqs. 17, 33, 34: finite, antisymmetric positions, baseline δ·f_U, tilts zero exactly when b_U = f_U."""
    with strict_floats():
        vg = g.view_geometry(cam)
        mask = g.views_inside_aperture(Camera(cam.pixel_pitch_mm, cam.mla_pitch_mm, cam.mla_focal_length_mm, MainLens(cam.main_optics.focal_length_mm, cam.main_optics.image_distance_mm, f_number=2.0)))
    c = cam.center_index
    assert list(vg.i) == list(range(-c, c + 1))
    assert np.all(np.isfinite(vg.position_mm)) and np.all(np.isfinite(vg.tilt_deg))
    np.testing.assert_array_equal(vg.position_mm, -vg.position_mm[::-1])
    assert np.all(np.abs(vg.tilt_deg) < 90.0)
    expected_baseline = Fr(cam.mla_pitch_mm) / cam.m_hat / Fr(cam.mla_focal_length_mm) * Fr(cam.main_optics.focal_length_mm)
    assert abs(Fr(vg.baseline_mm) - expected_baseline) <= 4 * U * expected_baseline
    if cam.main_optics.image_distance_mm == cam.main_optics.focal_length_mm:
        assert np.all(vg.tilt_deg == 0.0)
    assert mask.shape == (cam.m_hat, cam.m_hat) and mask[c, c]


# ---------------------------------------------------------------------------- focus distance
@fast(150)
@given(fu=log_uniform(0.1, 1000.0), fixed=st.floats(0.1, 100.0), factor=log_uniform(1.0 + 1e-9, 1e9))
def test_focus_distance_to_b_u_round_trip(fu, fixed, factor):
    """b_U from focus_distance_mm is never below f_U, and slice a = 0 lies back at the focus distance.

    The bound: b_U carries ~5 roundings, ε = b_U - f_U then has relative error 5U·b_U/ε, and
    k = D - fixed carries U·(D + fixed)/k; x = f_U²/ε inherits both; the rest is ulps of d.
    """
    k = 4.0 * fu * factor
    focus = k + fixed
    with strict_floats():
        b_u = focused(Camera(0.01, 0.25, fixed, MainLens(fu, fu)), focus).main_optics.image_distance_mm
    assert b_u >= fu
    cam = Camera(0.01, 0.25, fixed, MainLens(fu, b_u))
    eps = b_u - fu
    assume(eps > 0)
    with strict_floats():
        d0 = g.slice_distance_mm(cam, 0.0)
    x = fu * fu / eps
    bound = 16 * U * x * (b_u / eps + (focus + fixed) / k + 1) + 8 * U * (focus + fixed + fu + b_u)
    assert abs(d0 - focus) <= bound, (d0, focus, bound)


def test_focus_distance_beyond_double_resolution_is_infinity_not_nan():
    for focus in (1e18, 1e100, 1e300, math.inf):
        cam = focused(Camera(0.01, 0.25, 2.749, MainLens(99.5145, 99.5145)), focus)
        assert cam.main_optics.image_distance_mm >= 99.5145
        with strict_floats():
            d0 = g.slice_distance_mm(cam, 0.0)
        assert d0 >= min(focus, 1e15) and not math.isnan(d0)


# ---------------------------------------------------------------------------- slice planning
def check_plan(cam, near, far, a):
    """The plan covers [near, far]: finite increasing a, far end reached, no gap, near end reached."""
    assert a.ndim == 1 and len(a) >= 1 and np.all(np.isfinite(a)) and np.all(np.diff(a) > 0)
    with strict_floats():
        geo = g.slice_geometry(cam, a)
    if math.isinf(far):
        assert math.isinf(geo.far_mm[0])
    else:
        assert geo.far_mm[0] >= far
    assert geo.near_mm[-1] <= near
    assert np.all(geo.far_mm[1:] >= geo.near_mm[:-1])       # neighbouring intervals overlap: no gap


@fast(150)
@given(cam=cameras(min_ratio=3.0), start=log_uniform(1e-12, 1e3),
       width=st.one_of(st.just(0.0), log_uniform(1e-12, 1e6), st.just(math.inf)))
@example(cam=Camera(0.01, 0.25, 2.749, MainLens(99.5145, 99.5145)), start=1e-6, width=math.inf)
@example(cam=Camera(0.01, 0.25, 2.749, MainLens(99.5145, 109.5145)), start=1.0, width=0.0)
def test_plan_slices_covers_extreme_ranges_or_says_why(cam, start, width):
    closest = cam.main_optics.sensor_path_mm(cam.mla_path_mm) + cam.main_optics.focal_length_mm
    near = closest * (1.0 + start)
    far = near * (1.0 + width)
    assume(near > closest)
    try:
        with strict_floats():
            a = g.plan_slices(cam, near, far, max_slices=500)
    except LfprocError as exc:
        # ranges needing many slices, or so close to the front focal plane that a slice's DOF is below
        # the planner's 1e-9 relative overlap (sub-nm slices): a clean one-line refusal
        assert ("needs more than 500 slices" in str(exc) or "too thin to plan" in str(exc)) and "\n" not in str(exc)
        if "too thin" in str(exc):
            geo = g.slice_geometry(cam, g.refocus_parameter(cam, near))
            assert geo.dof_mm < 1e-8 * near
        return
    check_plan(cam, near, far, a)
    assert len(a) <= 500


def test_plan_slices_tiny_range_is_one_slice_and_infinite_range_reaches_infinity():
    cam = Camera(0.01, 0.25, 2.749, MainLens(99.5145, 99.5145))
    for near, far in ((250.0, 250.0), (250.0, 250.0 * (1 + 1e-15)), (250.0, math.inf), (210.0, math.inf),
                      (math.inf, math.inf)):
        a = g.plan_slices(cam, near, far)
        check_plan(cam, near, far, a)
        if far < 251:
            assert len(a) == 1
    # infinite range: the first slice's far limit is infinity and a is the infinity slice's neighbour
    a = g.plan_slices(cam, 300.0, math.inf)
    assert math.isinf(g.slice_geometry(cam, a[0]).far_mm)


@pytest.mark.parametrize("near, far, words", [
    (math.nan, 500.0, "not a valid range"), (300.0, math.nan, "not a valid range"),
    (500.0, 300.0, "not a valid range"), (-1.0, 300.0, "not a valid range"),
    (150.0, 300.0, "larger NEAR"), (201.0, 300.0, "larger NEAR")])
def test_plan_slices_rejects_impossible_ranges(near, far, words):
    cam = Camera(0.01, 0.25, 2.749, MainLens(99.5145, 99.5145))
    with pytest.raises(LfprocError) as excinfo:
        g.plan_slices(cam, near, far)
    one_line_error(excinfo, words)


def test_plan_slices_needs_three_pixel_micro_images():
    with pytest.raises(LfprocError) as excinfo:
        g.plan_slices(Camera(0.1, 0.25, 2.0, MainLens(100.0, 100.0)), 300.0, 400.0)    # m-hat = 1
    one_line_error(excinfo, "micro_image_px")


# ---------------------------------------------------------------------------- integer gaps
@fast(100)
@given(cam=cameras(min_ratio=3.0), top=st.integers(1, 60))
def test_integer_gaps_depend_only_on_m_hat(cam, top):
    """Slices a and a+1 leave a gap iff a+(a+1) > a-(a) (d decreases in a): an exact rational test in c.

    Only gaps whose exact width exceeds the rounding of both limits must be reported; overlaps wider than
    that must not.
    """
    c = cam.center_index
    ex = Exact(cam)
    with strict_floats():
        gaps = g.integer_slice_gaps(cam, range(top + 1))
    reported = {gap[0]: gap[1:] for gap in gaps}
    for a in range(top):
        a_minus = Fr(2 * a * c + 1, 2 * c - 1)
        a_plus_next = Fr(2 * (a + 1) * c - 1, 2 * c + 1)
        near_a = ex.distance(ex.border_z(a, inner=True))
        far_next = ex.distance(ex.border_z(a + 1, inner=False))
        assert (a_plus_next > a_minus) == (far_next < near_a)        # the c-only criterion, exactly
        alpha_error = 4 * U * (2 * (a + 1) * c + 1) / (2 * c - 1)
        tolerance = ex.error_bound(a_minus, alpha_error) + ex.error_bound(a_plus_next, alpha_error)
        width = float(near_a - far_next)
        if width > tolerance:
            assert a in reported
            lo, hi = reported[a]
            assert lo < hi and abs(Fr(lo) - far_next) <= Fr(tolerance) and abs(Fr(hi) - near_a) <= Fr(tolerance)
        elif width < -tolerance:
            assert a not in reported
    for lo, hi in reported.values():
        assert 0 < lo < hi < math.inf


# ============================================================================ refocus
def _snap(x):
    nearest = np.round(x)
    return np.where(np.abs(x - nearest) < 1e-9, nearest, x)


def _keys(x):
    """Keys (1981) cubic convolution kernel, a = -0.5 (Catmull-Rom), piecewise in |x|."""
    x = abs(x)
    if x <= 1:
        return 1.5 * x ** 3 - 2.5 * x ** 2 + 1
    return -0.5 * x ** 3 + 2.5 * x ** 2 - 4 * x + 2 if x < 2 else 0.0


def axis_reference(a, m, n, s, interpolation):
    """Per view index v: inside (m, P), dense weights (m, P, n) and tap-read mask (m, P, n) of one axis.

    Output p = q·s + r reads view v at q + snap(r/s + a(c - v)) (contract plus the module's
    documented upsampling and 1e-9 snapping); taps per the documented kernels, clamped to the edge.
    """
    c = (m - 1) // 2
    P = (n - 1) * s + 1
    spline = interpolation == "cubic-spline" and spline_axis(a, m, n, s)
    inside = np.zeros((m, P), bool)
    weights = np.zeros((m, P, n))
    read = np.zeros((m, P, n), bool)
    for v in range(m):
        for p in range(P):
            q, r = divmod(p, s)
            with np.errstate(over="ignore", invalid="ignore"):
                offset = float(_snap(np.float64(r / s + a * (c - v))))
            if not 0.0 <= q + offset <= n - 1:
                continue
            inside[v, p] = True
            base = q + math.floor(offset)
            t = offset - math.floor(offset)
            if interpolation == "nearest" or (interpolation == "cubic-spline" and not spline):
                taps = [(q + math.floor(offset + 0.5), 1.0)]
            elif interpolation == "cubic-spline":                # B-spline weights, whole lenses included
                taps = [(base + k, float(_bspline(t - k))) for k in (-1, 0, 1, 2)]
            elif t == 0.0:
                taps = [(base, 1.0)]
            elif interpolation == "linear":
                taps = [(base, 1.0 - t), (base + 1, t)]
            else:
                taps = [(base + k, _keys(t - k)) for k in (-1, 0, 1, 2)]
            for j, w in taps:
                j = min(max(j, 0), n - 1)
                weights[v, p, j] += w
                read[v, p, j] = True
    return inside, weights, read


def spline_axis(a, m, n, s):
    """Whether a cubic-spline slice takes B-spline weights along this axis: some inside sample lies
    between lenses (else it is a gather there)."""
    c = (m - 1) // 2
    for v in range(m):
        for p in range((n - 1) * s + 1):
            q, r = divmod(p, s)
            with np.errstate(over="ignore", invalid="ignore"):
                offset = float(_snap(np.float64(r / s + a * (c - v))))
            if 0.0 <= q + offset <= n - 1 and offset != math.floor(offset):
                return True
    return False


def refocus_reference(views, a, interpolation="linear", upsample=1):
    """Centred Eq. 9 in float64: mean over the inside samples, weights applied to the views; for
    cubic-spline then the B-spline's inverse filter along each axis that took B-spline weights
    (tests/test_refocus.py)."""
    views = np.asarray(views, dtype=np.float64)
    m, _, ny, nx, _ = views.shape
    iy, wy, _ = axis_reference(a, m, ny, upsample, interpolation)
    ix, wx, _ = axis_reference(a, m, nx, upsample, interpolation)
    total = np.einsum("vpi,wqj,vwijc->pqc", wy * iy[..., None], wx * ix[..., None], views)
    count = iy.sum(axis=0)[:, None] * ix.sum(axis=0)[None, :]
    assert count.min() >= 1
    out = total / count[..., None]
    for axis, n in ((0, ny), (1, nx)):
        if interpolation == "cubic-spline" and spline_axis(a, m, n, upsample):
            out = _spline_filter(out, upsample, axis)
    return out


def reached_pixels(shape, a, interpolation, upsample):
    """Boolean (m, m, Ny, Nx): the input pixels some counted sample of slice a reads."""
    m, _, ny, nx = shape[:4]
    iy, _, ry = axis_reference(a, m, ny, upsample, interpolation)
    ix, _, rx = axis_reference(a, m, nx, upsample, interpolation)
    reach_y = (iy[..., None] & ry).any(axis=1)         # (m, Ny)
    reach_x = (ix[..., None] & rx).any(axis=1)         # (m, Nx)
    return reach_y[:, None, :, None] & reach_x[None, :, None, :]


def random_views(shape, seed, dtype=np.float32):
    return np.random.default_rng(seed).random(shape).astype(dtype)


def float32_rtol(m):
    """Float32 row sums of m views, each sample a few roundings: relative error <= (m + 8)·U32, twice."""
    return (m + 8) * 2 * U32


refocus_a = st.one_of(st.integers(-6, 6).map(float), st.floats(-6.0, 6.0),
                      st.sampled_from([1e-12, -1e-12, 1e-10, 0.5, -0.5, 1e6, -1e6, 1e300, -1e300]))


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
@pytest.mark.parametrize("upsample", [1, 3])
def test_single_view_light_field_is_returned_unchanged(interpolation, upsample):
    """m-hat = 1: the central view is the only view and never moves, whatever a."""
    views = random_views((1, 1, 4, 6, 2), seed=1)
    out = rf.refocus(views, [0.0, 1.0, -2.5, 0.3, 1e-12, 1e9, -1e300], interpolation, upsample)
    expected = refocus_reference(views, 0.0, interpolation, upsample)
    # the spline overshoots to values near 0, whose float32 error is set by the views' scale (here < 1)
    atol = 4 * U32 if interpolation == "cubic-spline" else 0
    for k in range(out.shape[0]):
        np.testing.assert_allclose(out[k], expected, rtol=1e-6, atol=atol)
        if upsample == 1:
            np.testing.assert_array_equal(out[k], views[0, 0])


@pytest.mark.parametrize("a", [0.0, 1.0, -1.0, 0.02, 0.37, -0.5])
@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
def test_99_views_match_the_reference(a, interpolation):
    """m-hat = 99 (9801 views) on a small lens grid; a = 0.02 shifts the outer views by 0.98 lens."""
    views = random_views((99, 99, 3, 4, 1), seed=3)
    for upsample in (1, 2):
        out = rf.refocus(views, a, interpolation, upsample)
        np.testing.assert_allclose(out, refocus_reference(views, a, interpolation, upsample),
                                   rtol=float32_rtol(99), atol=float32_rtol(99))


@fast(60)
@given(m=st.sampled_from([1, 3, 5, 9]), long_side=st.integers(1, 7), axis=st.sampled_from(["rows", "cols", "both"]),
       a=refocus_a, interpolation=st.sampled_from(INTERPOLATIONS), upsample=st.integers(1, 3),
       channels=st.integers(1, 3), seed=st.integers(0, 2 ** 16))
def test_one_lens_wide_light_fields(m, long_side, axis, a, interpolation, upsample, channels, seed):
    ny, nx = {"rows": (1, long_side), "cols": (long_side, 1), "both": (1, 1)}[axis]
    views = random_views((m, m, ny, nx, channels), seed)
    out = rf.refocus(views, a, interpolation, upsample)
    assert out.shape == ((ny - 1) * upsample + 1, (nx - 1) * upsample + 1, channels) and out.dtype == np.float32
    np.testing.assert_allclose(out, refocus_reference(views, a, interpolation, upsample), rtol=2e-5, atol=2e-6)
    if axis == "both":
        # one lens: a view counts only where both its shifts snap to zero (|a(c - k)| < 1e-9)
        c = (m - 1) // 2
        with np.errstate(over="ignore", invalid="ignore"):
            counts = np.abs(a * (c - np.arange(m))) < 1e-9
        expected = views[counts][:, counts].astype(np.float64).mean(axis=(0, 1))
        np.testing.assert_allclose(out[0, 0], expected[0, 0], rtol=2e-6)


@fast(80)
@given(m=st.sampled_from([1, 3, 5, 9, 99]), ny=st.integers(1, 5), nx=st.integers(1, 5),
       dtype=st.sampled_from([np.float32, np.float64, np.uint16]), raw=st.floats(0.0, 1.0),
       a=st.lists(refocus_a, min_size=1, max_size=3), interpolation=st.sampled_from(INTERPOLATIONS),
       upsample=st.integers(1, 3))
@example(m=9, ny=3, nx=3, dtype=np.uint16, raw=1.0, a=[0.0, 1.0, 0.5, -1.3], interpolation="cubic", upsample=2)
def test_constant_images_stay_constant(m, ny, nx, dtype, raw, a, interpolation, upsample):
    """A constant light field refocuses to the same constant for every a, interpolation and upsampling."""
    if dtype is np.uint16:
        value = float(round(raw * 65535))
    else:
        value = float(np.float32(raw * 2.0e4 - 1.0e4))
    views = np.full((m, m, ny, nx, 1), value, dtype=dtype)
    out = rf.refocus(views, a, interpolation, upsample)
    assert out.dtype == np.float32 and np.all(np.isfinite(out))
    rtol = 2 * U32 if dtype is np.float64 else float32_rtol(m)
    np.testing.assert_allclose(out, value, rtol=rtol, atol=0)


@pytest.mark.parametrize("m", [1, 3, 9, 99])
def test_uint16_full_scale_means_are_exact(m):
    """uint16 up to 65535, whole-lens shifts: the float32 nearest to the exact integer mean, no overflow."""
    rng = np.random.default_rng(m)
    views = rng.integers(65000, 65536, size=(m, m, 3, 4, 2)).astype(np.uint16)
    views[..., 0, 0, :] = 65535
    for a, interpolation, upsample in [(0.0, "linear", 1), (1.0, "cubic", 1), (-2.0, "linear", 1),
                                       (0.4, "nearest", 1), (1.0, "linear", 2)]:
        out = rf.refocus(views, a, interpolation, upsample).astype(np.float64)
        exact = refocus_reference(views.astype(np.int64), a, interpolation, upsample)  # small integer sums: exact
        half_ulp = np.spacing(exact.astype(np.float32)).astype(np.float64) / 2
        assert np.all(np.abs(out - exact) <= half_ulp * (1 + 1e-9)), np.abs(out - exact).max()
        assert out.max() <= 65535.0
    full = np.full((m, m, 3, 4, 1), 65535, np.uint16)
    for interpolation in INTERPOLATIONS:
        np.testing.assert_array_equal(rf.refocus(full, [0, 2, -1], interpolation), 65535.0)
        frac = rf.refocus(full, [0.3, -1.7], interpolation, upsample=2)
        assert np.all(np.abs(frac - 65535.0) <= 65535.0 * float32_rtol(m))


@fast(60)
@given(m=st.sampled_from([3, 5, 9]), ny=st.integers(1, 6), nx=st.integers(1, 6), seed=st.integers(0, 2 ** 16),
       beyond=st.one_of(st.floats(1e-6, 10.0), st.sampled_from([1e6, 1e300])), sign=st.sampled_from([1.0, -1.0]),
       dtype=st.sampled_from([np.float32, np.float64, np.uint16]), interpolation=st.sampled_from(INTERPOLATIONS))
def test_large_a_leaves_exactly_the_central_view(m, ny, nx, seed, beyond, sign, dtype, interpolation):
    """|a| > N - 1 puts every sample of every non-central view outside: the output is the central view."""
    a = sign * (max(ny, nx) - 1 + beyond)
    views = (random_views((m, m, ny, nx, 2), seed, np.float64) * 60000).astype(dtype)
    c = (m - 1) // 2
    out = rf.refocus(views, a, interpolation)
    np.testing.assert_array_equal(out, views[c, c].astype(np.float32))
    # upsampled: the central view, interpolated on the finer grid (the m-hat = 1 light field of it)
    up = rf.refocus(views, a, interpolation, upsample=2)
    np.testing.assert_array_equal(up, rf.refocus(views[c:c + 1, c:c + 1], 0.0, interpolation, upsample=2))
    np.testing.assert_allclose(up, refocus_reference(views[c:c + 1, c:c + 1], 0.0, interpolation, 2),
                               rtol=2e-6, atol=60000 * 8 * U32)     # cubic: 4x4 taps of values up to 60000


def test_a_below_the_snap_tolerance_is_exactly_a_zero():
    """Documented: positions within 1e-9 lens of an integer are that integer, so a = 1e-12 is a = 0."""
    views = random_views((9, 9, 5, 6, 1), seed=5)
    for interpolation in INTERPOLATIONS:
        zero = rf.refocus(views, 0.0, interpolation)
        np.testing.assert_array_equal(rf.refocus(views, [1e-12, -2e-10], interpolation), np.stack([zero, zero]))
        np.testing.assert_allclose(zero, views.astype(np.float64).mean(axis=(0, 1)), rtol=float32_rtol(9))


@fast(80)
@given(m=st.sampled_from([1, 3, 5]), ny=st.integers(1, 6), nx=st.integers(1, 6), channels=st.integers(1, 2),
       where=st.tuples(st.integers(0, 4), st.integers(0, 4), st.integers(0, 5), st.integers(0, 5), st.integers(0, 1)),
       bad=st.sampled_from([np.nan, np.inf, -np.inf]), a=st.lists(refocus_a, min_size=1, max_size=3),
       interpolation=st.sampled_from(INTERPOLATIONS), upsample=st.integers(1, 2),
       dtype=st.sampled_from([np.float32, np.float64]), seed=st.integers(0, 1000))
def test_non_finite_pixels_raise_exactly_when_a_slice_reads_them(m, ny, nx, channels, where, bad, a, interpolation,
                                                                upsample, dtype, seed):
    """The module's documented handling: NaN/inf pixels that reach a slice raise LfprocError naming that
    slice; pixels that no counted sample reads (per the documented taps) are harmless."""
    views = random_views((m, m, ny, nx, channels), seed, dtype)
    ky, kx, jy, jx, ch = (w % n for w, n in zip(where, views.shape))
    clean = views.copy()
    views[ky, kx, jy, jx, ch] = bad
    reaches = [bool(reached_pixels(views.shape, ak, interpolation, upsample)[ky, kx, jy, jx]) for ak in a]
    if any(reaches):
        with pytest.raises(LfprocError) as excinfo:
            rf.refocus(views, a, interpolation, upsample)
        one_line_error(excinfo, "NaN or infinite", f"a={a[reaches.index(True)]:g}")
    else:
        out = rf.refocus(views, a, interpolation, upsample)
        assert np.all(np.isfinite(out))
        np.testing.assert_array_equal(out, rf.refocus(clean, a, interpolation, upsample))


@pytest.mark.parametrize("a", [[], (), np.array([]), np.empty((0,), np.float32), range(0)])
def test_empty_a_lists_are_user_errors(a):
    with pytest.raises(LfprocError) as excinfo:
        rf.refocus(random_views((3, 3, 2, 2, 1), 0), a)
    one_line_error(excinfo, "empty")


@pytest.mark.parametrize("a", [math.nan, math.inf, -math.inf, [0.0, math.nan], np.array([1.0, np.inf])])
def test_non_finite_a_is_a_user_error(a):
    with pytest.raises(LfprocError) as excinfo:
        rf.refocus(random_views((3, 3, 2, 2, 1), 0), a)
    one_line_error(excinfo, "finite")


@pytest.mark.parametrize("a, interpolation", [(0.0, "linear"), (1.0, "linear"), (-0.75, "linear"), (0.5, "cubic")])
def test_float64_views_keep_float64_precision(a, interpolation):
    """Views of ±1e8 plus O(1) detail: the big parts cancel between mirrored views, and only float64
    sums keep the detail (float32 sums would err by several units). Reference: float64 numpy, and the
    result is that mean rounded to float32."""
    m, ny, nx = 5, 6, 7
    views = random_views((m, m, ny, nx, 1), seed=9, dtype=np.float64)
    kx = np.arange(m)
    views += (1e8 * np.sign(kx - (m - 1) // 2))[None, :, None, None, None]
    out = rf.refocus(views, a, interpolation).astype(np.float64)
    ref = refocus_reference(views, a, interpolation)
    assert np.abs(ref).min() < 10.0                          # some pixels do cancel to O(1) values
    tolerance = np.spacing(np.abs(ref).astype(np.float32)).astype(np.float64) + 64 * m * m * U * 1e8
    assert np.all(np.abs(out - ref) <= tolerance), np.abs(out - ref).max()
    # and the float32 rounding of the same views really would lose that detail
    lossy = refocus_reference(views.astype(np.float32), a, interpolation)
    assert np.abs(lossy - ref).max() > 100 * tolerance.min()


def test_float32_values_near_the_top_of_the_range_average_without_overflow():
    """Finite float32 views whose mean is finite: the contract's mean, not an error about non-finite pixels.

    FAILS with lfproc/refocus.py as of issue 7: the per-view-row float32 partial sums overflow once
    values exceed float32 max / m-hat, and the output check then blames "NaN or infinite pixels" that
    the input does not have. Proposed fix (refocus.refocus, failure path only, no cost otherwise): when
    ``bad.any()`` and the views are float32 and all finite, render again from ``views.astype(float64)``
    (float64 row sums cannot overflow) and only then raise for slices that are still non-finite.
    """
    top = np.float32(3e38)
    views = np.full((3, 3, 4, 4, 1), top, np.float32)
    views[0, 0] = np.float32(1e38)
    out = rf.refocus(views, [0.0, 0.5], "linear")
    assert np.all(np.isfinite(out))
    expected = np.stack([refocus_reference(views, 0.0), refocus_reference(views, 0.5)])
    np.testing.assert_allclose(out, expected, rtol=1e-6)


# ============================================================================ decode
def aligned_grid(pitch, rows, cols, origin=None):
    c = (pitch - 1) / 2 if origin is None else origin
    return LensGrid("rectangular", float(pitch), 0.0, (c, c), rows, cols)


def micro_images(sensor, m, rows, cols):
    """Independent reference: micro image (r, q) is ``sensor[r*m:(r+1)*m, q*m:(q+1)*m]``;
    its pixel (ky, kx) is view (ky, kx)."""
    return sensor.reshape(rows, m, cols, m).transpose(1, 3, 0, 2)[..., None]


@pytest.mark.parametrize("interpolation", ["nearest", "linear", "cubic", "lanczos"])
def test_decode_with_one_pixel_micro_images(interpolation):
    """m-hat = 1: each lens gives one sample, the sensor at the lens centre divided by the white image."""
    rows, cols, pitch = 3, 5, 4
    rng = np.random.default_rng(11)
    sensor = rng.random((rows * pitch, cols * pitch)).astype(np.float32)
    white = (0.5 + rng.random(sensor.shape)).astype(np.float32)
    grid = LensGrid("rectangular", float(pitch), 0.0, (1.0, 2.0), rows, cols)       # centres on whole pixels
    views = decode(sensor, white, grid, 1, interpolation=interpolation)
    assert views.shape == (1, 1, rows, cols, 1) and np.all(np.isfinite(views))
    r, q = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    expected = sensor[2 + pitch * r, 1 + pitch * q] / white[2 + pitch * r, 1 + pitch * q]
    np.testing.assert_allclose(views[0, 0, :, :, 0], expected, rtol=1e-6)


@pytest.mark.parametrize("m", [1, 3, 5, 25])
@pytest.mark.parametrize("interpolation", ["nearest", "linear"])
def test_decode_a_one_lens_sensor(m, interpolation):
    rng = np.random.default_rng(m)
    sensor = rng.random((m, m)).astype(np.float32)
    white = (0.25 + rng.random((m, m))).astype(np.float32)
    views = decode(sensor, white, aligned_grid(m, 1, 1), m, interpolation=interpolation)
    assert views.shape == (m, m, 1, 1, 1)
    np.testing.assert_allclose(views, micro_images(sensor / white, m, 1, 1), rtol=1e-6)


def test_decode_a_one_pixel_sensor_under_a_larger_lens():
    """Samples outside a 1x1 sensor read a black white image: they decode to 0, the centre to s/w."""
    views = decode(np.array([[0.3]], np.float32), np.array([[0.6]], np.float32), aligned_grid(3, 1, 1, 0.0), 3)
    expected = np.zeros((3, 3, 1, 1, 1), np.float32)
    expected[1, 1] = 0.5
    np.testing.assert_allclose(views, expected, rtol=1e-6, atol=0)


@pytest.mark.parametrize("interpolation", ["nearest", "linear"])
def test_white_image_with_zeros_and_negatives_decodes_without_nan(interpolation):
    """Dark white samples (zeros, noise below zero) decode to 0; the others to capture / white."""
    m, rows, cols = 5, 4, 6
    rng = np.random.default_rng(4)
    white = (0.5 + 0.5 * rng.random((rows * m, cols * m))).astype(np.float32)
    white[rng.random(white.shape) < 0.3] = 0.0
    white[rng.random(white.shape) < 0.05] = -1e-3
    sensor = rng.random(white.shape).astype(np.float32)
    w = micro_images(white, m, rows, cols)
    s = micro_images(sensor, m, rows, cols)
    signal = w > 0.05 * np.percentile(w, 99)          # the documented dark_fraction rule, default 0.05
    expected = np.where(signal, s / np.where(signal, w, 1.0), 0.0)
    # every view delivered: sample by sample
    views = decode(sensor, white, aligned_grid(m, rows, cols), m, interpolation=interpolation,
                   centroid_tolerance=None)
    assert np.all(np.isfinite(views))
    np.testing.assert_allclose(views, expected, rtol=1e-6, atol=0)
    # the default delivers the views this speckled white image lights (the others are 0), by the same rule
    decoder = make_decoder(white, aligned_grid(m, rows, cols), m, interpolation=interpolation)
    views = decoder(sensor)
    delivered = decoder.views_delivered
    assert np.all(np.isfinite(views)) and np.all(views[~delivered] == 0.0)
    np.testing.assert_allclose(views[delivered], expected[delivered], rtol=1e-6, atol=0)


def test_white_image_with_zeros_on_a_rotated_grid_has_no_nan():
    rng = np.random.default_rng(6)
    white = rng.random((60, 70)).astype(np.float32)
    white[:, ::3] = 0.0
    white[::4, :] = 0.0
    grid = LensGrid("rectangular", 6.7, 3.0, (4.2, 3.9), 8, 9)
    for interpolation in ("nearest", "linear", "cubic", "lanczos"):
        views = decode(rng.random((60, 70)).astype(np.float32), white, grid, 5, interpolation=interpolation)
        assert np.all(np.isfinite(views))
        if interpolation in ("nearest", "linear"):     # non-negative weights: no ringing below zero
            assert views.min() >= 0.0


@pytest.mark.parametrize("cfa", ["none", "RGGB"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_white_pixels_are_a_user_error(cfa, bad):
    """Even where no sample reads them, and for Bayer white images too (demosaicing must not hide them)."""
    m, rows, cols = 5, 4, 4
    white = np.ones((rows * m + 3, cols * m + 3), np.float32)
    for where in ((7, 7), (rows * m + 2, cols * m + 2)):              # read by a sample / outside all lenses
        broken = white.copy()
        broken[where] = bad
        with pytest.raises(LfprocError) as excinfo:
            make_decoder(broken, aligned_grid(m, rows, cols), m, cfa)
        one_line_error(excinfo, "white image", "NaN or infinite")


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_pixels_in_a_bayer_capture_are_not_silently_zeroed(bad):
    """A capture with NaN or inf pixels, Bayer or mono, is refused with one line (a Bayer one must
    never turn into a light field of zeros, a mono one never carry NaN into the views)."""
    m, rows, cols = 5, 4, 4
    capture = np.full((rows * m, cols * m), 0.3, np.float32)
    capture[7, 7] = bad
    for cfa in ("RGGB", "none"):
        dec = make_decoder(np.ones_like(capture), aligned_grid(m, rows, cols), m, cfa)
        with pytest.raises(LfprocError) as excinfo:
            dec(capture)
        one_line_error(excinfo, "NaN or infinite")


# ============================================================================ LightField
@pytest.mark.parametrize("shape", [(2, 2, 3, 3, 1), (4, 4, 1, 1, 1), (98, 98, 1, 1, 1), (3, 5, 2, 2, 1),
                                   (5, 3, 2, 2, 1), (1, 3, 2, 2, 1), (0, 0, 2, 2, 1), (3, 3, 0, 2, 1),
                                   (3, 3, 2, 0, 1), (3, 3, 2, 2, 0), (3, 3, 2, 2), (3, 3, 2, 2, 1, 1)])
def test_even_non_square_or_empty_view_counts_are_user_errors(shape):
    with pytest.raises(LfprocError) as excinfo:
        LightField.from_views(np.zeros(shape, np.float32))
    one_line_error(excinfo, str(shape))
    with pytest.raises(LfprocError):
        LightField(np.zeros(shape, np.float32))


def test_camera_with_another_m_hat_is_a_user_error():
    with pytest.raises(LfprocError) as excinfo:
        LightField.from_views(np.zeros((3, 3, 2, 2, 1)), Camera(0.01, 0.25, 2.749, MainLens(99.5, 99.5)))
    one_line_error(excinfo, "micro_image_px")


EXTREME_CAMERA = Camera(1e-3, 1.0, 0.1, MainLens(1000.0, 1000.0 + 1e-12, principal_plane_gap_mm=-499.999999, f_number=1e-3), mla_principal_plane_gap_mm=-0.05, micro_image_px=99, name='we"ird \\ name ü', cfa="GBRG", black_level=-1e-300, white_level=1e300)


@pytest.mark.parametrize("shape", [(1, 1, 1, 1, 1), (99, 99, 1, 2, 1), (1, 1, 1, 600, 3), (3, 3, 300, 1, 2),
                                   (5, 5, 2, 3, 7)])
def test_save_load_round_trip_of_extreme_shapes(tmp_path, shape):
    views = random_views(shape, seed=sum(shape)) * 2 - 1
    special = np.array([np.finfo(np.float32).max, -np.finfo(np.float32).max, np.finfo(np.float32).smallest_subnormal,
                        -0.0, np.nan, np.inf, -np.inf], np.float32)
    flat = views.reshape(-1)
    flat[:min(len(special), flat.size)] = special[:flat.size]
    camera = EXTREME_CAMERA if shape[0] == 99 else None
    grid = LensGrid("hexagonal", 13.37, -0.5, (1e-3, 2.5e5), shape[2], shape[3], 1e-300) if shape[0] != 1 else None
    lf = LightField.from_views(views, camera, grid)
    path = tmp_path / "x.lfp.npz"
    lf.save(path)
    lf.save(path)                                          # overwriting an existing file works
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.lfp.npz"]    # no temporary left behind
    back = LightField.load(path)
    assert back.views.dtype == np.float32 and back.views.shape == shape
    np.testing.assert_array_equal(back.views.view(np.uint32), lf.views.view(np.uint32))   # bit-exact, NaN too
    assert back.camera == camera and back.grid == grid
    if camera is not None:
        assert back.camera.main_optics.image_distance_mm - back.camera.main_optics.focal_length_mm == pytest.approx(1e-12, rel=0.2)
        assert back.camera.name == camera.name


def test_loading_a_truncated_file_is_a_user_error(tmp_path):
    path = tmp_path / "x.lfp.npz"
    LightField.from_views(random_views((3, 3, 4, 4, 1), 0)).save(path)
    path.write_bytes(path.read_bytes()[: os.path.getsize(path) // 2])
    with pytest.raises(LfprocError) as excinfo:
        LightField.load(path)
    one_line_error(excinfo, str(path))


def test_float64_views_beyond_float32_are_refused():
    from lfproc import LfprocError, LightField

    views = np.full((3, 3, 2, 2, 1), 1e39)
    with pytest.raises(LfprocError, match="float32 range"):
        LightField.from_views(views)
    assert LightField.from_views(np.full((3, 3, 2, 2, 1), 3e38)).views.max() == np.float32(3e38)
