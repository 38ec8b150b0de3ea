"""`lfproc.refocus` (centred Eq. 9) against an independent plain-numpy implementation of the contract.

The reference below is written from the contract's formula, not from the module: it computes every
sample position per output pixel, builds a dense 1-D interpolation matrix per view axis from the
interpolation kernels' textbook definitions (the piecewise Keys kernel, not the module's polynomial
weights), and counts the inside samples pixel by pixel. ``"cubic-spline"`` is the cubic B-spline kernel
on the views and then, on the slice, the inverse of the sampled B-spline (1/6, 2/3, 1/6) along each axis
with mirror-symmetric ends, as a dense matrix inverse: in the interior the mean of the views' cubic
spline interpolants (checked against scipy's map_coordinates in tests/test_interpolation_bias.py).
"""

import contextlib
import importlib
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lfproc
from lfproc import LfprocError, LightField

rf = importlib.import_module("lfproc.refocusing._refocus")      # the driver: _views_array, _bands, MIN_BAND_ROWS
rf_plan = importlib.import_module("lfproc.refocusing._plan")     # axis_plan, keys_cubic_weights
rf_kernels = importlib.import_module("lfproc.refocusing._kernels")

INTERPOLATIONS = ("nearest", "linear", "cubic", "cubic-spline")
RTOL, ATOL = 2e-5, 2e-5


# ------------------------------------------------------------------ independent reference
def _snap(x):
    r = np.round(x)
    return np.where(np.abs(x - r) < 1e-9, r, x)


def _keys(x):
    """Keys (1981) cubic convolution kernel with a = -0.5, piecewise in |x|."""
    x = np.abs(x)
    return np.where(x <= 1, 1.5 * x**3 - 2.5 * x**2 + 1,
                    np.where(x < 2, -0.5 * x**3 + 2.5 * x**2 - 4 * x + 2, 0.0))


def _bspline(x):
    """The cubic B-spline, piecewise in |x|."""
    x = np.abs(x)
    return np.where(x <= 1, 2 / 3 - x**2 + x**3 / 2, np.where(x < 2, (2 - x) ** 3 / 6, 0.0))


def _spline_inverse(n):
    """(n, n): B-spline coefficients from samples — the inverse of the sampled B-spline, mirror ends."""
    if n == 1:
        return np.ones((1, 1))
    t = np.zeros((n, n))
    for i in range(n):
        for j in (i - 1, i, i + 1):
            k = abs(j) if j < n else 2 * (n - 1) - j          # mirror-symmetric about 0 and n − 1
            t[i, k] += _bspline(i - j)
    return np.linalg.inv(t)


def _spline_filter(out, s, axis):
    """The inverse filter along ``axis`` of each phase r of an s-times upsampled axis."""
    out = np.moveaxis(out.copy(), axis, 0)
    for r in range(s):
        out[r::s] = np.einsum("ij,j...->i...", _spline_inverse(len(out[r::s])), out[r::s])
    return np.moveaxis(out, 0, axis)


def _interp_matrix(pos, n, interpolation):
    """Dense (len(pos), n) matrix: row p samples a length-n signal at pos[p] (rows outside [0, n-1] are 0)."""
    w = np.zeros((len(pos), n))
    for p, x in enumerate(pos):
        if not 0 <= x <= n - 1:
            continue
        if interpolation == "nearest":
            w[p, int(np.floor(x + 0.5))] = 1.0
        elif interpolation == "linear":
            i = int(np.floor(x))
            t = x - i
            w[p, i] += 1 - t
            w[p, min(i + 1, n - 1)] += t
        elif interpolation == "cubic-spline":
            i = int(np.floor(x))
            for j in range(i - 1, i + 3):
                w[p, min(max(j, 0), n - 1)] += _bspline(x - j)
        else:
            i = int(np.floor(x))
            for j in range(i - 1, i + 3):
                w[p, min(max(j, 0), n - 1)] += _keys(x - j)
    return w


def reference(views, a, interpolation="linear", upsample=1, mask=None):
    """out[py, px] = mean over inside (ky, kx) of views[ky, kx] sampled at (py/s + a(c-ky), px/s + a(c-kx)),
    over the views ``mask`` marks (all without one); 0 where no marked view is inside."""
    views = np.asarray(views, dtype=np.float64)
    m, _, ny, nx, channels = views.shape
    c = (m - 1) // 2
    s = upsample
    py = np.arange((ny - 1) * s + 1) / s
    px = np.arange((nx - 1) * s + 1) / s

    def kind(positions, n):
        """cubic-spline along an axis with no sample between lenses is a gather there."""
        pos = _snap(np.concatenate([positions + a * (c - k) for k in range(m)]))
        between = ((pos % 1 != 0) & (pos >= 0) & (pos <= n - 1)).any()
        return interpolation if interpolation != "cubic-spline" or between else "nearest"

    kind_y, kind_x = kind(py, ny), kind(px, nx)
    total = np.zeros((len(py), len(px), channels))
    count = np.zeros((len(py), len(px)))
    for ky in range(m):
        y = _snap(py + a * (c - ky))
        wy = _interp_matrix(y, ny, kind_y)
        for kx in range(m):
            if mask is not None and not mask[ky, kx]:
                continue
            x = _snap(px + a * (c - kx))
            wx = _interp_matrix(x, nx, kind_x)
            inside = ((0 <= y) & (y <= ny - 1))[:, None] & ((0 <= x) & (x <= nx - 1))[None, :]
            sampled = np.einsum("pi,ijc,qj->pqc", wy, views[ky, kx], wx)
            total += np.where(inside[..., None], sampled, 0.0)
            count += inside
    if mask is None:
        assert count.min() >= 1
    out = np.where(count[..., None] > 0, total / np.maximum(count, 1)[..., None], 0.0)
    if kind_y == "cubic-spline":
        out = _spline_filter(out, s, 0)
    if kind_x == "cubic-spline":
        out = _spline_filter(out, s, 1)
    return out


def random_views(m, ny, nx, channels, seed=0, dtype=np.float32):
    return np.random.default_rng(seed).random((m, m, ny, nx, channels)).astype(dtype)


def close(actual, expected):
    np.testing.assert_allclose(actual, expected, rtol=RTOL, atol=ATOL)


# ------------------------------------------------------------------ against the reference
@pytest.mark.parametrize("m, ny, nx", [(1, 5, 6), (3, 7, 9), (5, 8, 7), (9, 6, 10), (25, 4, 5)])
@pytest.mark.parametrize("channels", [1, 3])
def test_integer_a_matches_reference(m, ny, nx, channels):
    views = random_views(m, ny, nx, channels, seed=m)
    for a in (0, 1, -2, 3, -7):   # |a|·c ≥ N for the larger ones: most samples fall outside
        out = lfproc.refocus(views, a)
        assert out.shape == (ny, nx, channels) and out.dtype == np.float32
        close(out, reference(views, a))


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
@pytest.mark.parametrize("m, channels", [(1, 1), (3, 3), (5, 1), (9, 3)])
def test_real_a_matches_reference(interpolation, m, channels):
    views = random_views(m, 9, 11, channels, seed=3 * m + channels)
    for a in (0.5, -0.5, 0.3, -1.25, 2.7, -4.6):
        close(lfproc.refocus(views, a, interpolation), reference(views, a, interpolation))


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
def test_upsampled_matches_reference(interpolation):
    views = random_views(5, 6, 7, 3, seed=11)
    for a, s in ((1.0, 2), (-0.75, 3), (2.4, 4)):
        out = lfproc.refocus(views, a, interpolation, upsample=s)
        assert out.shape == (5 * s + 1, 6 * s + 1, 3)
        close(out, reference(views, a, interpolation, s))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(m=st.sampled_from([1, 3, 5, 7]), ny=st.integers(1, 9), nx=st.integers(1, 9), channels=st.sampled_from([1, 3]),
       a=st.one_of(st.integers(-6, 6).map(float), st.floats(-6, 6, allow_nan=False)),
       interpolation=st.sampled_from(INTERPOLATIONS), upsample=st.integers(1, 3), seed=st.integers(0, 99))
def test_random_cases_match_reference(m, ny, nx, channels, a, interpolation, upsample, seed):
    views = random_views(m, ny, nx, channels, seed)
    close(lfproc.refocus(views, a, interpolation, upsample), reference(views, a, interpolation, upsample))


def test_offsets_with_rounding_error_count_as_whole_lenses():
    """1.1·10 = 11.000000000000002 in floating point: snapped to 11, so the view is read without
    interpolation and its last row (position exactly N − 1) still counts."""
    plan = rf_plan.axis_plan([1.1], m=21, n=14, upsample=1, interpolation="linear")
    assert plan.offset[0, 0, 0] == 11.0 and plan.ntaps[0, 0, 0] == 1 and plan.hi[0, 0, 0] == 2
    views = random_views(21, 14, 3, 1, seed=12)
    close(lfproc.refocus(views, 1.1, "cubic"), reference(views, 1.1, "cubic"))


@pytest.mark.parametrize("threads", [1, 3])
def test_many_small_bands_match_reference(monkeypatch, threads):
    """A tiny accumulator budget forces one-row bands, run inline or on a pool: the split changes nothing."""
    monkeypatch.setattr(rf, "ACCUMULATOR_BUDGET_BYTES", 8)
    monkeypatch.setattr(rf, "MIN_BAND_ROWS", 1)
    monkeypatch.setattr(rf, "_thread_count", lambda: threads)
    assert len(rf._bands(2, 13, 18, threads)) == 13
    views = random_views(5, 13, 6, 3, seed=5)
    for a in (2, -1.5):
        close(lfproc.refocus(views, [a, a + 1]), np.stack([reference(views, a), reference(views, a + 1)]))


def test_bands_cover_every_row_once():
    for n_slices, n_rows, row_len, threads in ((1, 434, 1875, 2), (5, 434, 1875, 2), (100, 434, 1875, 2),
                                               (1, 1, 3, 4), (3, 7, 5, 16)):
        bands = rf._bands(n_slices, n_rows, row_len, threads)
        assert [r for lo, hi in bands for r in range(lo, hi)] == list(range(n_rows))
        assert len(bands) % threads == 0 or len(bands) == n_rows
        assert min(hi - lo for lo, hi in bands) >= min(rf.MIN_BAND_ROWS, n_rows // threads)


# ------------------------------------------------------------------ hand-checked semantics
def test_one_dimensional_example_of_eq_8():
    """Ny = 1: only the central view row is inside; out[j] = mean over kx of views[c, kx, 0, j + a(c - kx)]."""
    views = np.zeros((3, 3, 1, 6, 1), np.float32)
    views[:, :, 0, :, 0] = np.arange(3)[None, :, None] * 100 + np.arange(6)[None, None, :]  # value 100·kx + jx
    views[0] += 5000  # view rows other than c = 1 must not contribute
    out = lfproc.refocus(views, 1.0)[0, :, 0]
    # j = 2: kx = 0 reads jx 3 (3), kx = 1 reads 2 (102), kx = 2 reads 1 (201)
    assert out[2] == pytest.approx((3 + 102 + 201) / 3)
    # j = 0: kx = 2 would read jx -1 (outside): mean of kx = 0 (jx 1) and kx = 1 (jx 0)
    assert out[0] == pytest.approx((1 + 100) / 2)
    # j = 5: kx = 0 would read jx 6 (outside)
    assert out[5] == pytest.approx((105 + 204) / 2)


def test_border_counts_by_hand():
    """Views of constant value 10·ky + kx, a = 1, m = 3: each pixel averages exactly the views inside."""
    m, n = 3, 4
    views = np.zeros((m, m, n, n, 1), np.float32)
    for ky in range(m):
        for kx in range(m):
            views[ky, kx] = 10 * ky + kx
    out = lfproc.refocus(views, 1)[..., 0]
    inside = {0: [0, 1], 1: [0, 1, 2], 2: [0, 1, 2], 3: [1, 2]}   # j + (1 - k) ∈ [0, 3]
    for jy in range(n):
        for jx in range(n):
            expected = np.mean([10 * ky + kx for ky in inside[jy] for kx in inside[jx]])
            assert out[jy, jx] == pytest.approx(expected)


def test_huge_a_leaves_only_the_central_view():
    views = random_views(5, 6, 7, 3, seed=2)
    for a in (1e6, -3.5e9, 1e308):
        for interpolation in INTERPOLATIONS:
            out = lfproc.refocus(views, a, interpolation)
            np.testing.assert_array_equal(out, views[2, 2])


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
def test_a_zero_is_the_plain_mean_of_views(interpolation):
    views = random_views(7, 5, 8, 3, seed=4)
    close(lfproc.refocus(views, 0.0, interpolation), views.astype(np.float64).mean(axis=(0, 1)))


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
def test_constant_light_field_stays_constant(interpolation):
    views = np.full((5, 5, 6, 9, 3), 0.625, np.float32)
    out = lfproc.refocus(views, [0, 1, -2.3, 0.5, 40.0], interpolation, upsample=2)
    np.testing.assert_allclose(out, 0.625, rtol=1e-6)


@pytest.mark.parametrize("interpolation, exact_margin", [("linear", 0), ("cubic", 3)])
def test_refocusing_at_the_planes_slope_recovers_it(interpolation, exact_margin):
    """A Lambertian plane of slope a0 (view k sees g shifted by -a0(c - k)) comes back as g at a = a0.

    g is linear (reproduced by bilinear everywhere) plus, for cubic, a quadratic term: Keys reproduces
    quadratics wherever no tap is clamped, i.e. where every counted sample lies in [1, N − 2]; with
    offsets up to a0·c = 1.5 that is three lenses in from the border.
    """
    m, n, a0 = 5, 16, 0.75
    c = (m - 1) // 2

    def g(y, x):
        value = 0.3 + 0.05 * y - 0.02 * x
        return value + (0.001 * x * x if interpolation == "cubic" else 0.0)

    jy, jx = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    views = np.stack([np.stack([g(jy - a0 * (c - ky), jx - a0 * (c - kx)) for kx in range(m)]) for ky in range(m)])
    out = lfproc.refocus(views[..., None].astype(np.float64), a0, interpolation)[..., 0]
    core = slice(exact_margin, n - exact_margin)
    np.testing.assert_allclose(out[core, core], g(jy, jx)[core, core], rtol=0, atol=2e-6)


# ------------------------------------------------------------------ dtypes and precision
def test_uint16_near_full_scale_never_overflows():
    rng = np.random.default_rng(7)
    views = (65535 - rng.integers(0, 40, size=(9, 9, 6, 7, 3))).astype(np.uint16)
    for a in (0, 1, -0.5):
        out = lfproc.refocus(views, a, "cubic")
        assert out.min() > 65400 and out.max() <= 65535.5
        np.testing.assert_allclose(out, reference(views, a, "cubic"), rtol=1e-6, atol=0)
    # integer a on integer data: per-view-row sums are exact, so the mean is exact to float32 rounding
    np.testing.assert_allclose(lfproc.refocus(views, 2), reference(views, 2), rtol=6e-8, atol=0)


def _cancelling_row(dtype):
    """View row 0 holds 1e8, 0.5 and −1e8: its sum is 0.5 in float64 but 0.0 in float32 (1e8 + 0.5 rounds
    to 1e8), so the a = 0 mean over the 25 views is 0.02 only when the row is summed in float64."""
    views = np.zeros((5, 5, 3, 4, 1), dtype=dtype)
    views[0, 0] = 1e8
    views[0, 1] = 0.5
    views[0, 2] = -1e8
    return views


def test_float64_input_is_summed_in_float64():
    assert np.float32(np.float32(1e8) + np.float32(0.5)) - np.float32(1e8) == 0.0   # the trap is real
    out = lfproc.refocus(_cancelling_row(np.float64), 0)
    assert out.dtype == np.float32
    np.testing.assert_allclose(out, 0.5 / 25, rtol=1e-6)


def test_longdouble_input_is_read_as_float64():
    views = _cancelling_row(np.longdouble)
    assert rf._views_array(views).dtype == np.float64
    np.testing.assert_allclose(lfproc.refocus(views, 0), 0.5 / 25, rtol=1e-6)


def test_finite_float64_beyond_float32_range_says_rescale():
    views = np.full((3, 3, 4, 4, 1), 1e300)
    with pytest.raises(LfprocError, match="exceed the float32 range; rescale") as info:
        lfproc.refocus(views, 0)
    assert "NaN" not in str(info.value)
    views[0, 0, 1, 1, 0] = np.nan      # really non-finite input keeps the NaN message
    with pytest.raises(LfprocError, match="NaN or infinite"):
        lfproc.refocus(views, 0)


@pytest.mark.parametrize("interpolation", ["cubic", "cubic-spline"])
def test_overshoot_beyond_float32_says_rescale(recwarn, interpolation):
    """Finite float32 views with a step up to 3.4e38: cubic kernels overshoot the float32 range between
    lenses. That is a range problem (rescale), not NaN input, and no numpy warning reaches stderr."""
    views = np.zeros((3, 3, 12, 12, 1), np.float32)
    views[:, :, :, 6:] = np.float32(3.4e38)
    views[:, :, :, 8] = 0.0
    with pytest.raises(LfprocError, match="exceed the float32 range.*rescale") as info:
        lfproc.refocus(views, 0.5, interpolation)
    assert "NaN" not in str(info.value) and not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_other_input_dtypes_and_lightfield_agree():
    views = (random_views(3, 5, 6, 1, seed=8) * 200).astype(np.uint8)
    expected = reference(views, 1.5)
    close(lfproc.refocus(views, 1.5), expected)
    close(lfproc.refocus(views.astype(np.int32), 1.5), expected)
    close(lfproc.refocus(LightField.from_views(views), 1.5), expected)


# ------------------------------------------------------------------ several slices, shapes, dispatch
def test_stack_equals_separate_calls_exactly():
    views = random_views(7, 10, 12, 3, seed=9)
    for slopes in ([0, 1, 2, -3, 5], [0.5, -1.25, 2, 3.75]):
        for interpolation in INTERPOLATIONS:
            stacked = lfproc.refocus(views, slopes, interpolation)
            separate = np.stack([lfproc.refocus(views, a, interpolation) for a in slopes])
            np.testing.assert_array_equal(stacked, separate)


def test_upsample_one_is_plain_and_upsampled_grid_contains_the_plain_one():
    views = random_views(5, 6, 8, 3, seed=10)
    for a in (2, 0.4):
        plain = lfproc.refocus(views, a, "cubic")
        np.testing.assert_array_equal(lfproc.refocus(views, a, "cubic", upsample=1), plain)
        close(lfproc.refocus(views, a, "cubic", upsample=3)[::3, ::3], plain)


def test_scalar_and_sequence_shapes():
    views = random_views(3, 4, 5, 3)
    assert lfproc.refocus(views, 1).shape == (4, 5, 3)
    assert lfproc.refocus(views, np.float32(1.5)).shape == (4, 5, 3)
    assert lfproc.refocus(views, np.array(2)).shape == (4, 5, 3)
    assert lfproc.refocus(views, [1]).shape == (1, 4, 5, 3)
    assert lfproc.refocus(views, (0, 1.5, -2)).shape == (3, 4, 5, 3)
    assert lfproc.refocus(views, np.arange(4)).shape == (4, 4, 5, 3)
    np.testing.assert_array_equal(lfproc.refocus(views, [1.5])[0], lfproc.refocus(views, 1.5))


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
def test_integer_a_is_a_pure_gather(monkeypatch, interpolation):
    """Integer a (and nearest, any a) at upsample 1 never reaches the interpolating kernel."""
    def forbidden(*args):
        raise AssertionError("interpolating kernel used for whole-lens shifts")
    monkeypatch.setattr(rf, "_interpolated_band", forbidden)
    monkeypatch.setattr(rf, "_interpolated_rows_band", forbidden)     # the upsample-1 interpolating kernel
    views = random_views(5, 6, 7, 1)
    lfproc.refocus(views, [0, 3, -1], interpolation)
    lfproc.refocus(views, [0.37, -2.5], "nearest")
    real_a_interpolates = pytest.raises(AssertionError) if interpolation != "nearest" else contextlib.nullcontext()
    with real_a_interpolates:
        lfproc.refocus(views, 0.5, interpolation)


def test_axis_plan_weights_sum_to_one_and_counts_are_separable():
    plan = rf_plan.axis_plan([0.3, -1.7, 2.0], m=5, n=9, upsample=2, interpolation="cubic")
    used = np.arange(4)[None, None, None, :] < plan.ntaps[..., None]
    np.testing.assert_allclose(np.where(used, plan.weights, 0).sum(axis=-1), 1.0, atol=1e-12)
    assert plan.count.shape == (3, 17) and plan.count.min() >= 1 and plan.count.max() <= 5
    np.testing.assert_allclose(rf_plan.keys_cubic_weights(np.array([0.0]))[0], [0, 1, 0, 0])


# ------------------------------------------------------------------ errors
@pytest.mark.parametrize("a, words", [([], "empty"), (float("nan"), "finite"), ([0, float("inf")], "finite"),
                                      ("1", "not a number"), ([True], "not a number"), ([[1, 2]], "flat")])
def test_bad_a_is_a_user_error(a, words):
    with pytest.raises(LfprocError, match=words):
        lfproc.refocus(random_views(3, 4, 4, 1), a)


def test_bad_arguments_are_user_errors():
    views = random_views(3, 4, 4, 1)
    with pytest.raises(LfprocError, match="interpolation"):
        lfproc.refocus(views, 1, "bicubic")
    for bad in (0, -1, 1.5, True):
        with pytest.raises(LfprocError, match="upsample"):
            lfproc.refocus(views, 1, upsample=bad)
    with pytest.raises(LfprocError, match="GiB"):            # ~36 TB of output: refused before allocating
        lfproc.refocus(views, 1, upsample=10**6)
    for shape in ((3, 3, 4, 4), (2, 2, 4, 4, 1), (3, 5, 4, 4, 1), (3, 3, 0, 4, 1)):
        with pytest.raises(LfprocError, match="shaped"):
            lfproc.refocus(np.zeros(shape, np.float32), 1)
    with pytest.raises(LfprocError, match="real-valued"):
        lfproc.refocus(np.zeros((3, 3, 4, 4, 1), np.complex64), 1)


def test_output_size_limit_is_exact(monkeypatch):
    """K·Ny'·Nx'·C·4 bytes: 2 slices × 7 × 9 × 1 × 4 = 504 bytes for (4, 5) lenses at upsample 2."""
    views = random_views(3, 4, 5, 1)
    monkeypatch.setattr(rf, "MAX_OUTPUT_BYTES", 504)
    assert lfproc.refocus(views, [0, 1], upsample=2).nbytes == 504
    monkeypatch.setattr(rf, "MAX_OUTPUT_BYTES", 503)
    with pytest.raises(LfprocError, match="upsample=2"):
        lfproc.refocus(views, [0, 1], upsample=2)


def test_non_finite_pixels_that_reach_a_slice_are_a_user_error():
    views = random_views(3, 5, 5, 1)
    views[0, 0, 4, 4, 0] = np.nan        # read by a = 0, outside of every sample for a = 10
    np.testing.assert_array_equal(lfproc.refocus(views, 10.0), views[1, 1])
    with pytest.raises(LfprocError, match="a=0"):
        lfproc.refocus(views, [10, 0])
    views[0, 0, 4, 4, 0] = np.inf
    with pytest.raises(LfprocError, match="NaN or infinite"):
        lfproc.refocus(views, 0.5, "cubic")


# ------------------------------------------------------------------ numba on-disk cache
def _kernel_cache_misses_and_hits_in_a_new_process():
    code = ("import importlib, numpy as np, lfproc\n"
            "rf_kernels = importlib.import_module('lfproc.refocusing._kernels')\n"
            "v = np.ones((3, 3, 4, 5, 1), np.float32)\n"
            "lfproc.refocus(v, [0, 1]); lfproc.refocus(v, 0.5); lfproc.refocus(v, 0.5, upsample=2)\n"
            "k = (rf_kernels._gather_band, rf_kernels._interpolated_rows_band, rf_kernels._interpolated_band)\n"
            "print(*(sum(sum(getattr(f.stats, n).values()) for f in k) for n in ('cache_misses', 'cache_hits')))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return tuple(map(int, proc.stdout.split()))


def test_second_process_loads_kernels_from_cache():
    """cache=True: a new process loads the three kernels from numba's on-disk cache instead of compiling.

    The cache is shared with anything else that runs lfproc in this tree at the same moment, which may
    rewrite it (another source stamp): then the first probe compiles, and the next one must not.
    """
    lfproc.refocus(random_views(3, 4, 5, 1), [0, 1])     # compiles (or loads) and saves in this process
    lfproc.refocus(random_views(3, 4, 5, 1), 0.5)
    lfproc.refocus(random_views(3, 4, 5, 1), 0.5, upsample=2)
    misses, hits = _kernel_cache_misses_and_hits_in_a_new_process()
    if misses:
        misses, hits = _kernel_cache_misses_and_hits_in_a_new_process()
    assert (misses, hits) == (0, 3)


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
@pytest.mark.parametrize("upsample", [1, 2])
def test_a_view_mask_averages_only_the_views_that_carry_light(interpolation, upsample):
    """Views the decoder leaves at 0 (outside the aperture, at micro image rims) do not darken slices."""
    m = 5
    views = random_views(m, 9, 11, 2, seed=7)
    yy, xx = np.mgrid[:m, :m] - (m - 1) / 2
    mask = yy ** 2 + xx ** 2 <= 2.5                      # a disc of 9 views, like an aperture
    views[~mask] = 0.0
    lf = LightField.from_views(views, view_mask=mask)
    for a in (0.0, 1.0, -1.7, 3.4):
        close(lfproc.refocus(lf, a, interpolation, upsample), reference(views, a, interpolation, upsample, mask))
    # a constant scene stays constant wherever a marked view reaches the pixel
    flat = np.where(mask[:, :, None, None, None], np.float32(0.6), np.float32(0.0)) * np.ones((1, 1, 9, 11, 1))
    out = lfproc.refocus(LightField.from_views(flat, view_mask=mask), [0.5, 2.0], interpolation, upsample)
    assert np.allclose(out[out > 0], 0.6, rtol=1e-5) and (out > 0).mean() > 0.5


def test_a_full_view_mask_is_no_mask():
    views = random_views(3, 4, 5, 1)
    assert LightField.from_views(views, view_mask=np.ones((3, 3), bool)).view_mask is None
    with pytest.raises(LfprocError, match="view_mask"):
        LightField.from_views(views, view_mask=np.zeros((3, 3), bool))


def test_the_view_mask_survives_the_light_field_file(tmp_path):
    views = random_views(3, 4, 5, 1)
    mask = np.array([[False, True, False], [True, True, True], [False, True, False]])
    LightField.from_views(views, view_mask=mask).save(tmp_path / "x.lfp.npz")
    loaded = LightField.load(tmp_path / "x.lfp.npz")
    np.testing.assert_array_equal(loaded.view_mask, mask)
    close(lfproc.refocus(loaded, 1.0), reference(views, 1.0, mask=mask))


def _dark_outside_a_disc(faint: float, m: int = 5, ny: int = 9, nx: int = 11):
    """Views whose 9 central ones (a disc, like an aperture) carry light everywhere (0.2 … 1) and whose 16
    others are ``faint`` times as bright: 0, as the decoder delivers views without light, or a faint rest."""
    views = random_views(m, ny, nx, 2, seed=11) * np.float32(0.8) + np.float32(0.2)
    yy, xx = np.mgrid[:m, :m] - (m - 1) / 2
    lit = yy ** 2 + xx ** 2 <= 2.5
    views[~lit] *= np.float32(faint)
    return views, lit


@pytest.mark.parametrize("faint", [0.0, 1e-3])
def test_an_array_with_dark_views_keeps_the_contracts_mean_and_says_what_to_pass(faint):
    """Issue 31: an array has no view mask, so its mean runs over every view (the contract's formula, as it
    stands) and is darker than the LightField's; one LfprocWarning, at the caller, says why and what to pass."""
    from lfproc import LfprocWarning

    views, lit = _dark_outside_a_disc(faint)
    a_values = [0.0, 1.0, -1.7]
    for call in (lfproc.refocus, importlib.import_module("lfproc.refocusing").refocus):
        with pytest.warns(LfprocWarning) as said:
            out = call(views, a_values)
        assert len(said) == 1 and said[0].filename == __file__   # the caller's line, not lfproc's
    text = str(said[0].message)
    assert "16 of 25 views of this array are dark" in text and "about 0.36x as bright" in text
    assert "pass the LightField (lf, not lf.views)" in text
    assert "lfproc.LightField.from_views(views, camera, view_mask=...) with the 9 views" in text
    for k, a in enumerate(a_values):   # the contract's mean over all views, the dark ones included
        close(out[k], reference(views, a))
    masked = lfproc.refocus(LightField.from_views(views, view_mask=lit), a_values)
    for k, a in enumerate(a_values):
        close(masked[k], reference(views, a, mask=lit))
    # at a = 0 every pixel averages every view: the array's slice is 9/25 of the LightField's, plus the faint rest
    expected = 9 / 25 * (1 + views[~lit].astype(np.float64).sum() / views[lit].astype(np.float64).sum())
    assert float(out[0].mean() / masked[0].mean()) == pytest.approx(expected, rel=1e-5)


def test_an_array_whose_every_view_carries_light_is_refocused_without_a_warning(recwarn):
    """No warning where no view is dark: a dim (vignetted) view at 5 %, black rows, a view dark in every row
    the cheap first look samples but lit in the others, and an array that is 0 everywhere."""
    m, ny = 5, 32
    views = random_views(m, ny, 7, 1, seed=3)
    views[0, 0] *= np.float32(0.05)               # dim, not dark: 5 % of the others
    views[1, 1, 5:9] = 0.0                        # black rows inside a view
    views[2, 3, ::2] = 0.0                        # the first look reads every second row: it looks dark there
    a_values = [0.0, 1.0]
    out = lfproc.refocus(views, a_values)
    for k, a in enumerate(a_values):
        close(out[k], reference(views, a))
    lfproc.refocus(np.zeros((3, 3, 4, 4, 1), np.float32), 1.0)
    assert not [w for w in recwarn if issubclass(w.category, lfproc.LfprocWarning)]
    from lfproc.refocusing._refocus import lit_views
    assert lit_views(views) is None
    views[4, 4] *= np.float32(0.009)              # under 1 % of the brightest view: dark
    lit = lit_views(views)
    assert lit is not None and not lit[4, 4] and lit.sum() == m * m - 1
