"""The finite exit pupil and triangulation (issue 12) against PlenoptiSign 1.1.3, a plain ray trace,
the telecentric formulas, and at the extremes."""

import dataclasses
import math

import numpy as np
import pytest

from focus import focused
from lfproc import Camera, LfprocError
from lfproc import geometry as g
from lfproc.camera import MainLens

# PlenoptiSign is the independent implementation of Hahne et al. (IJCV 2018) that the issue names as
# the oracle; it is a test dependency (pyproject's [test] extra, pure Python), imported outright so that
# the comparison can never be skipped silently.
import plenoptisign  # noqa: E402


# ------------------------------------------------------------------ helpers
def ps_run(cam, a, gap, dx, df):
    """PlenoptiSign on our camera: its pp is our effective pixel pitch, M our m-hat, distances from H1s."""
    obj = plenoptisign.MainClass(dict(pp=cam.sample_pitch_mm, fs=cam.mla_focal_length_mm,
                                      hh=cam.mla_principal_plane_gap_mm, pm=cam.mla_pitch_mm,
                                      dA=cam.main_optics.exit_pupil_distance_mm, fU=cam.main_optics.focal_length_mm,
                                      HH=cam.main_optics.principal_plane_gap_mm, df=df, M=cam.m_hat, a=a, G=gap, dx=dx))
    obj.refo()
    obj.tria()
    return obj


def random_camera(rng):
    """A camera with a finite exit pupil, focused at infinity (b_U set by PlenoptiSign later) or nearer."""
    m = int(rng.choice([5, 7, 9, 11, 13, 15]))
    pm = float(rng.uniform(0.01, 0.2))
    fs = float(rng.uniform(0.02, 3.0))
    fu = float(rng.uniform(10.0, 200.0))
    mla_gap = float(rng.uniform(-0.1, 0.5)) * fs          # drawn in this order, as the cameras always were
    main_gap = float(rng.uniform(-0.5, 0.3)) * fu
    d_a = float(rng.uniform(20.0, 200.0) if rng.random() < 0.85 else rng.uniform(0.5, 20.0))
    return Camera(pm / m * 0.999, pm, fs, MainLens(fu, fu, main_gap, exit_pupil_distance_mm=d_a),
                  mla_principal_plane_gap_mm=mla_gap, micro_image_px=m)


def ray_trace_z(cam, rays):
    """z from H1U where two image-side rays (lens height s, slope m) meet in object space (Eqs. 16-20)."""
    fu, bu = cam.main_optics.focal_length_mm, cam.main_optics.image_distance_mm
    lines = []
    for s, m in rays:
        u = s + m * bu
        lines.append(((m * fu - u) / fu, u))
    (q1, u1), (q2, u2) = lines
    return (u2 - u1) / (q1 - q2)


def chief_slope(cam, s, i):
    """Image-side slope of pixel i counted from the micro image centre under the lens at height s."""
    centre = s * cam.micro_image_scale
    return (s - (centre + i * cam.sample_pitch_mm)) / cam.mla_focal_length_mm


# ------------------------------------------------------------------ PlenoptiSign's default camera
def test_plenoptisign_default_camera_numbers():
    """d = 962.7459, B = 3.7956, Z = 5869.2898 mm: its defaults (a = 1, G = -6, dx = 1, focus at infinity)."""
    default = plenoptisign.MainClass()
    default.refo()
    default.tria()
    model = g.RayModel(sample_pitch_mm=0.009, mla_pitch_mm=0.125, mla_focal_length_mm=2.75,
                       main_focal_length_mm=193.2935, image_distance_mm=193.2935, micro_image_px=13.9523,
                       mla_principal_plane_gap_mm=0.396, main_principal_plane_gap_mm=-65.5563,
                       exit_pupil_distance_mm=111.0324)
    to_h1s = 2.75 + 0.396                     # PlenoptiSign measures from the MLA's H1s, we from the sensor
    geo = g.slice_geometry(model, 1.0)
    tri = g.triangulate(model, 1.0, gap=-6)
    assert round(geo.distance_mm - to_h1s, 4) == 962.7459
    assert round(tri.baseline_mm, 4) == 3.7956
    assert round(tri.range_mm, 4) == 5869.2898
    assert tri.distance_mm == pytest.approx(tri.range_mm + g.virtual_camera_plane_mm(model), rel=1e-12)
    for ours, theirs in ((geo.distance_mm - to_h1s, default.d), (geo.far_mm - to_h1s, default.d_p),
                         (geo.near_mm - to_h1s, default.d_m), (tri.baseline_mm, default.B),
                         (tri.range_mm, default.Z)):
        assert ours == pytest.approx(float(theirs), rel=1e-9)


# ------------------------------------------------------------------ 250 random cameras
def test_agreement_with_plenoptisign_on_random_cameras():
    rng = np.random.default_rng(2018)
    compared = {"d": 0, "dof": 0, "B": 0, "phi": 0, "Z": 0}
    for _ in range(250):
        cam0 = random_camera(rng)
        df = math.inf if rng.random() < 0.25 else float(rng.uniform(5, 50)) * cam0.main_optics.focal_length_mm
        a = float(rng.uniform(-1.0, 5.0))
        gap = int(rng.choice([-6, -3, -1, 1, 2, 5]))
        dx = float(rng.uniform(-5.0, 5.0))
        probe = plenoptisign.MainClass(dict(fU=cam0.main_optics.focal_length_mm, HH=cam0.main_optics.principal_plane_gap_mm, df=df))
        probe.compute_img_dist()
        cam = cam0.with_optics(dataclasses.replace(cam0.main_optics, image_distance_mm=float(probe.bU)))   # the same b_U, to the last bit
        ps = ps_run(cam, a, gap, dx, df)
        to_h1s = cam.mla_focal_length_mm + cam.mla_principal_plane_gap_mm
        fu, eps = cam.main_optics.focal_length_mm, cam.main_optics.image_distance_mm - cam.main_optics.focal_length_mm
        geo = g.slice_geometry(cam, a)
        tri = g.triangulate(cam, dx, gap)
        # slice distance: PlenoptiSign calls every slice whose image-side rays meet short of f_U "out of
        # range" (inf), including those that meet in front of the main lens (z < f_U, the macro regime):
        # there we stay finite, below the front focal plane, and equal to the plain ray trace.
        if math.isinf(ps.d) and math.isfinite(geo.distance_mm):
            assert "out of range" in ps.console_msg
            assert geo.distance_mm < cam.main_optics.sensor_path_mm(cam.mla_path_mm) + fu
            c_s = cam.mla_pitch_mm * 3.0
            z = ray_trace_z(cam, [(0.0, chief_slope(cam, 0.0, 0)), (-a * cam.mla_pitch_mm, chief_slope(cam, -a * cam.mla_pitch_mm, 1))])
            assert geo.distance_mm == pytest.approx(cam.main_optics.sensor_path_mm(cam.mla_path_mm) + z, rel=1e-9), c_s
        else:
            assert_same(geo.distance_mm - to_h1s, ps.d)
            compared["d"] += 1
            c = cam.center_index
            ps_lo, ps_hi = sorted((float(ps.d_m), float(ps.d_p)))
            if a >= 1.0 / (2 * c) and not math.isinf(ps.d_m):
                assert_same(geo.near_mm - to_h1s, ps_lo)
                assert_same(geo.far_mm - to_h1s, ps_hi)
                compared["dof"] += 1
            elif math.isfinite(geo.distance_mm):
                # below a = 1/(2c) a DOF limit lies beyond the focus distance, where this model takes the
                # border rays that bound the beams (test_geometry_beyond_focus.py): it contains PlenoptiSign's
                assert geo.near_mm - to_h1s <= ps_lo * (1 + 1e-9) and geo.far_mm - to_h1s >= ps_hi * (1 - 1e-9)
        assert_same(tri.baseline_mm, ps.B)
        assert_same(tri.tilt_deg, ps.phi, floor=1e-12)
        compared["B"] += 1
        compared["phi"] += 1
        if math.isinf(ps.Z) and math.isfinite(tri.range_mm):
            # PlenoptiSign's shortcut: focus at infinity and dx <= 0 always gives inf. The rays say
            # otherwise for dx < 0 (a finite Z of sign -G, in front of or behind the virtual cameras)
            assert eps == 0.0 and dx < 0
            assert tri.range_mm == pytest.approx(tri.baseline_mm * fu / (dx * cam.mla_pitch_mm
                                                                         * (1 - eps / cam.main_optics.exit_pupil_distance_mm)))
        else:
            assert_same(tri.range_mm, ps.Z)
            compared["Z"] += 1
    assert min(compared.values()) >= 150, compared


def assert_same(ours, theirs, rel=1e-6, floor=0.0):
    theirs = float(theirs)
    if math.isinf(theirs):
        assert math.isinf(ours), (ours, theirs)
    else:
        assert math.isfinite(ours) and abs(ours - theirs) <= rel * abs(theirs) + floor, (ours, theirs)


# ------------------------------------------------------------------ the same ray model, traced step by step
@pytest.mark.parametrize("d_a", [46.0, 111.0, 3.0])
@pytest.mark.parametrize("a", [-0.7, 0.0, 0.4, 2.0])
def test_central_distance_is_the_ray_intersection_with_drifted_micro_images(d_a, a):
    cam = focused(Camera(0.0014, 0.02, 0.0406, MainLens(30.0, 30.0, exit_pupil_distance_mm=d_a), micro_image_px=13), 900.0)
    for s0 in (0.0, 1.7, -4.2):                         # any pair of neighbouring views, anywhere on the MLA
        s1 = s0 - a * cam.mla_pitch_mm
        z = ray_trace_z(cam, [(s0, chief_slope(cam, s0, 3)), (s1, chief_slope(cam, s1, 4))])
        expected = cam.main_optics.sensor_path_mm(cam.mla_path_mm) + z if z > 0 else math.inf
        assert g.slice_distance_mm(cam, a) == pytest.approx(expected, rel=1e-9)


def test_triangulated_point_is_where_the_two_views_rays_meet():
    cam = focused(Camera(0.0014, 0.02, 0.0406, MainLens(30.0, 30.0, exit_pupil_distance_mm=46.0), micro_image_px=13), 700.0)
    for gap, dx in ((1, -0.3), (-6, 0.8), (4, 1.6), (2, 0.0)):
        s_first, s_second = 0.6, 0.6 + dx * cam.mla_pitch_mm      # view i under one lens, view i+G dx lenses on
        z = ray_trace_z(cam, [(s_first, chief_slope(cam, s_first, -2)), (s_second, chief_slope(cam, s_second, -2 + gap))])
        tri = g.triangulate(cam, dx, gap)
        assert tri.distance_mm == pytest.approx(cam.main_optics.sensor_path_mm(cam.mla_path_mm) + z, rel=1e-9)
        # the virtual cameras: two rays of one view meet at the plane and lateral position given
        zc = ray_trace_z(cam, [(0.0, chief_slope(cam, 0.0, gap)), (0.3, chief_slope(cam, 0.3, gap))])
        assert g.virtual_camera_plane_mm(cam) == pytest.approx(cam.main_optics.sensor_path_mm(cam.mla_path_mm) + zc, rel=1e-9)
        assert g.view_positions_mm(cam, [gap])[0] == pytest.approx(tri.baseline_mm, rel=1e-12)


def test_triangulation_of_a_slice_disparity_is_the_slice_distance():
    cam = focused(Camera(0.0014, 0.02, 0.0406, MainLens(30.0, 30.0, exit_pupil_distance_mm=46.0), micro_image_px=13), 700.0)
    a = np.linspace(-2.0, 3.0, 41)
    for gap in (1, 3, -5):
        np.testing.assert_array_equal(g.triangulate(cam, 0.0, gap, a=a).distance_mm, g.slice_distance_mm(cam, a))
        np.testing.assert_allclose(g.triangulate(cam, -a * gap, gap).distance_mm, g.slice_distance_mm(cam, a),
                                   rtol=1e-12)


# ------------------------------------------------------------------ telecentric: exactly the 2014 numbers
def old_formulas(cam, a):
    """The telecentric closed forms as they were before the exit pupil (plain numpy, same operation order)."""
    fu, eps, pm = cam.main_optics.focal_length_mm, cam.main_optics.image_distance_mm - cam.main_optics.focal_length_mm, cam.mla_pitch_mm
    delta = (pm / cam.m_hat) / cam.mla_focal_length_mm

    def d(x):
        denom = x * pm + delta * eps
        with np.errstate(all="ignore"):
            z = fu + fu * fu * delta / denom
        meets = (denom > 0) | ((denom < 0) & (z > 0))
        return cam.main_optics.sensor_path_mm(cam.mla_path_mm) + np.where(meets & np.isfinite(z), z, np.inf)

    c = cam.center_index
    return d(a), d((2.0 * a * c + 1.0) / (2.0 * c - 1.0)), d((2.0 * a * c - 1.0) / (2.0 * c + 1.0)), delta


@pytest.mark.parametrize("name", ["paper-f100", "paper-f100-b10", "paper-f200-b10", "paper-f100-fs1623"])
def test_telecentric_results_are_bit_for_bit_the_2014_closed_forms(name):
    from conftest import SAMPLES
    cam = Camera.from_toml(SAMPLES / "cameras" / f"{name}.toml")
    assert cam.telecentric and g.micro_image_scale(cam) == 1.0
    a = np.concatenate([np.linspace(-3, 8, 221), [1.0 / (2 * cam.center_index) + 1e-9]])
    d, near, far, delta = old_formulas(cam, a)
    geo = g.slice_geometry(cam, a)
    np.testing.assert_array_equal(geo.distance_mm, d)
    positive = a >= 1.0 / (2 * cam.center_index)             # the paper's domain: limits in front of the focus
    finite = positive & np.isfinite(far)
    np.testing.assert_array_equal(geo.near_mm[finite], near[finite])
    np.testing.assert_array_equal(geo.far_mm[finite], far[finite])
    i = g.view_offsets(cam)
    np.testing.assert_array_equal(g.view_positions_mm(cam, i), (-i * delta + 0.0) * cam.main_optics.focal_length_mm)
    assert g.baseline_mm(cam, 3) == 3.0 * delta * cam.main_optics.focal_length_mm
    dist = d[np.isfinite(d) & (a > 0)]
    x = dist - cam.main_optics.sensor_path_mm(cam.mla_path_mm) - cam.main_optics.focal_length_mm
    eps = cam.main_optics.image_distance_mm - cam.main_optics.focal_length_mm
    np.testing.assert_array_equal(g.refocus_parameter(cam, dist),
                                  delta * (cam.main_optics.focal_length_mm ** 2 * (1.0 / x) - eps) / cam.mla_pitch_mm)


# ------------------------------------------------------------------ extremes
def illum_like(d_a=46.048875898122787, focus=1000.0):
    return focused(Camera(0.0014, 0.02, 0.0406, MainLens(77.59, 77.59, f_number=2.11, exit_pupil_distance_mm=d_a), grid="hexagonal", micro_image_px=13), focus)


def test_exit_pupil_towards_infinity_converges_to_telecentric():
    a = np.array([-2.0, -0.5, 0.0, 0.3, 1.0, 4.0])
    tele = g.slice_geometry(illum_like(math.inf), a)
    for d_a in (1e6, 1e9, 1e12, 1e15):
        geo = g.slice_geometry(illum_like(d_a), a)
        for key in ("distance_mm", "near_mm", "far_mm"):
            np.testing.assert_allclose(getattr(geo, key), getattr(tele, key), rtol=200.0 / d_a)
        assert abs(g.baseline_mm(illum_like(d_a), 1) / g.baseline_mm(illum_like(math.inf), 1) - 1) < 10.0 / d_a


def test_exit_pupil_towards_the_mla_collapses_every_slice_onto_the_focus_distance():
    focus = illum_like(math.inf, 1000.0)
    for d_a in (1e-3, 1e-6, 1e-9, 1e-12):
        cam = focus.with_optics(dataclasses.replace(focus.main_optics, exit_pupil_distance_mm=d_a))
        with np.errstate(all="raise", under="ignore"):
            geo = g.slice_geometry(cam, np.array([-1.5, 0.5, 2.0]))
            tri = g.triangulate(cam, np.array([-1.0, 0.0, 2.0]), 1)
        for arr in (geo.distance_mm, geo.near_mm, geo.far_mm, tri.distance_mm):
            assert np.all(np.isfinite(arr)) and np.all(np.abs(arr / 1000.0 - 1) < 1e3 * d_a + 1e-9), arr
        assert np.all(geo.near_mm <= geo.distance_mm) and np.all(geo.distance_mm <= geo.far_mm)


def test_a_and_disparity_towards_zero_are_continuous():
    cam = illum_like()
    d0 = g.slice_distance_mm(cam, 0.0)
    assert d0 == pytest.approx(1000.0, rel=1e-12)               # a = 0 stays the focus distance with d_A
    for tiny in (1e-6, 1e-9, 1e-12, 0.0):
        assert g.slice_distance_mm(cam, tiny) == pytest.approx(d0, rel=1e-3 * tiny / 1e-6 + 1e-12)
        assert g.triangulate(cam, -tiny, 1).distance_mm == pytest.approx(d0, rel=1e-3 * tiny / 1e-6 + 1e-12)
    at_inf = g.triangulate(illum_like(focus=math.inf), 0.0, 2)
    assert math.isinf(at_inf.distance_mm) and math.isinf(at_inf.range_mm)


def test_micro_image_scale_and_its_inverse():
    cam = illum_like()
    scale = g.micro_image_scale(cam)
    assert scale == pytest.approx((46.048875898122787 + 0.0406) / 46.048875898122787, rel=1e-15)
    assert g.exit_pupil_from_scale(scale, cam) == pytest.approx(46.048875898122787, rel=1e-9)
    assert math.isinf(g.exit_pupil_from_scale(1.0, cam))
    assert cam.sample_pitch_mm == pytest.approx(0.02 * scale / 13, rel=1e-15)
    assert cam.effective_pixel_pitch_mm == 0.02 / 13                 # the contract's, unchanged
    assert math.isinf(g.exit_pupil_from_scale(0.9999, cam))       # fit noise around 1: no drift
    np.testing.assert_allclose(g.exit_pupil_from_scale(np.array([1.001, 1.01]), cam), [40.6, 4.06], rtol=1e-9)
    with pytest.raises(LfprocError, match="not a positive number"):
        g.exit_pupil_from_scale(math.nan, cam)


def test_triangulate_is_vectorised_and_refuses_a_zero_gap():
    cam = illum_like()
    dx = np.linspace(-3, 3, 12).reshape(3, 4)
    tri = g.triangulate(cam, dx, np.array([[1], [2], [-3]]))
    assert tri.distance_mm.shape == (3, 4) and tri.baseline_mm.shape == (3, 4)
    assert math.isnan(g.triangulate(cam, math.nan, 1).distance_mm)
    with pytest.raises(LfprocError, match="gap"):
        g.triangulate(cam, 1.0, 0)


def test_wide_random_cameras_with_exit_pupils_give_no_nan_and_ordered_limits():
    """Pitches 1 um-1 mm, focal lengths 0.1 mm-1 m, b_U - f_U in {0} U [1e-12, 1e3] mm, d_A 1e-9 mm-1e12 mm,
    a from -50 to 50 and the slice at infinity: no warning, no NaN, nothing negative, near <= d <= far."""
    rng = np.random.default_rng(7)

    def log_uniform(lo, hi):
        return float(10 ** rng.uniform(math.log10(lo), math.log10(hi)))

    checked = 0
    for _ in range(600):
        pixel, lens = sorted((log_uniform(1e-3, 1.0), log_uniform(1e-3, 1.0)))
        fu = log_uniform(0.1, 1000.0)
        eps = 0.0 if rng.random() < 0.2 else log_uniform(1e-12, 1e3)
        cam = Camera(pixel, lens, log_uniform(0.1, 1000.0), MainLens(fu, fu + eps, exit_pupil_distance_mm=log_uniform(1e-9, 1e12)))
        a = np.concatenate([rng.uniform(-50, 50, 20), [0.0, -1.0, 1.0, g.infinity_parameter(cam)]])
        with np.errstate(all="raise", under="ignore"):
            geo = g.slice_geometry(cam, a)
            tri = g.triangulate(cam, rng.uniform(-5, 5, 5), 2)
            views = g.view_geometry(cam)
        for arr in (geo.distance_mm, geo.near_mm, geo.far_mm, geo.dof_mm, tri.distance_mm):
            assert not np.isnan(arr).any() and (arr >= 0).all()
        assert (geo.near_mm <= geo.distance_mm).all() and (geo.distance_mm <= geo.far_mm).all()
        assert np.all(np.isfinite(views.tilt_deg))
        checked += 1
    assert checked == 600
