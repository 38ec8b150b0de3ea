"""A finite exit pupil in the simulator: micro images drift outwards to s·(d_A + f_s)/d_A, measured on the white
image by intensity centroids (independent of lfproc's calibration), against plain-numpy Monte Carlo ray
tracing through the exit pupil, and bit-identity of the telecentric case."""

import hashlib
import math
from dataclasses import replace

import numpy as np
import pytest

from lfproc import geometry, simulate
from lfproc.camera import Camera, MainLens
from lfproc.errors import LfprocError
from lfproc.simulate import Noise, Plane, Scene, Uniform, parse_scene_dict
from plainref import shifted_views

F_U, H_U, F_S, H_S = 99.5145, -33.184, 2.749, 0.374  # the paper's f100 main lens and micro lens


def camera(pixel_mm=0.009, f_number=13.0, grid="rectangular", exit_pupil_distance_mm=float("inf"), **kw):
    """The paper's camera (p_m = 0.25 mm), focused at infinity."""
    return Camera(pixel_mm, 0.25, F_S, MainLens(F_U, F_U, H_U, f_number, exit_pupil_distance_mm),
                  mla_principal_plane_gap_mm=H_S, grid=grid, **kw)


def centroids(white, expected_xy, radius_px):
    """Intensity centroid of the white image in a disk of radius_px + 2 around each expected centre: (n, 2)."""
    yy, xx = np.mgrid[0:white.shape[0], 0:white.shape[1]]
    out = []
    for cx, cy in expected_xy:
        window = (xx - cx) ** 2 + (yy - cy) ** 2 <= (radius_px + 2) ** 2
        w = white[window].astype(np.float64)
        out.append(((w * xx[window]).sum() / w.sum(), (w * yy[window]).sum() / w.sum()))
    return np.array(out)


@pytest.mark.parametrize("kind, rotation, d_a", [("rectangular", 1.7, 30.0), ("hexagonal", -2.3, 60.0),
                                                 ("rectangular", 0.0, 150.0)])
def test_white_micro_images_sit_on_the_scaled_lattice(kind, rotation, d_a):
    """Micro image centroids = lens centres scaled by (d_A + f_s)/d_A about the axis, within 0.05 px; the drift
    itself reaches several pixels at the border."""
    cam = camera(grid=kind, exit_pupil_distance_mm=d_a)  # disk radius f_s/2N = 11.7 px < half pitch
    shape = (260, 300)
    white, grid = simulate.render_white(cam, shape, rotation_deg=rotation, offset_px=(0.37, -0.21),
                                        rim_radius_mm=None, pixel_samples=4)
    cap_lenses = simulate.render(cam, Scene(()), (260, 300), rotation_deg=rotation, offset_px=(0.37, -0.21),
                                 rim_radius_mm=None, ideal_views=False).lens_grid
    scale = (d_a + F_S) / d_a
    axis = np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2])
    lens_xy = cap_lenses.centers_xy_px().reshape(-1, 2)
    # the lens lattice: pitch p_m/p_p, a lens at the axis + offset (the telecentric default placement)
    assert cap_lenses.pitch_px == pytest.approx(0.25 / 0.009)
    assert np.min(np.hypot(*(lens_xy - axis - (0.37, -0.21)).T)) < 1e-9
    expected = axis + scale * (lens_xy - axis)
    np.testing.assert_allclose(grid.centers_xy_px().reshape(-1, 2), expected, atol=1e-9)
    measured = centroids(white, expected, F_S / 26.0 / 0.009)
    errors = np.hypot(*(measured - expected).T)
    drift = np.hypot(*(expected - lens_xy).T)
    assert len(errors) >= 20 and errors.max() < 0.05
    assert drift.max() > (4.0 if d_a < 100 else 2.0)  # the drift is real: far beyond the tolerance


def test_white_matches_monte_carlo_rays_through_the_exit_pupil():
    """Per-pixel white values near a border lens equal the fraction of (pixel point, lens aperture point) pairs
    whose image-space ray meets the exit pupil disk (diameter d_A/N at d_A in front of the MLA), in plain numpy."""
    d_a, n_f = 25.0, 12.0  # disk radius f_s/(2N) = 5 px inside a micro image cell of ±6.1 px
    cam = camera(pixel_mm=0.25 / 11, f_number=n_f, exit_pupil_distance_mm=d_a)
    shape = (165, 231)
    radiance = simulate.render_radiance(cam, None, shape, rim_radius_mm=None, pixel_samples=8, aperture_samples=8,
                                        channels=1)[..., 0]
    lenses = simulate.render(cam, Scene(()), shape, rim_radius_mm=None, ideal_views=False).lens_grid
    axis = np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2])
    rng = np.random.default_rng(3)
    row, col = 1, lenses.cols - 2  # a lens near the corner: a drift of about 1.5 mm·f_s/d_A = 7 px
    s = (lenses.lens_xy(row, col) - axis) * cam.pixel_pitch_mm
    centre_px = axis + (s / cam.pixel_pitch_mm) * (d_a + F_S) / d_a
    cx, cy = np.rint(centre_px).astype(int)
    n = 20_000
    for dy in range(-5, 6):
        for dx in range(-5, 6):
            x = (np.array([cx + dx, cy + dy]) - axis + rng.uniform(-0.5, 0.5, (n, 2))) * cam.pixel_pitch_mm
            t = s + rng.uniform(-0.125, 0.125, (n, 2))  # lens aperture point (square cell, no rotation)
            slope = (s - x) / F_S
            at_pupil = t + slope * d_a
            reference = (np.hypot(*at_pupil.T) <= d_a / (2 * n_f)).mean()
            # MC σ ≤ 0.0036; the renderer's 8×8 pixel × 8×8 aperture strata err by < 0.01 on the disk's edge
            assert radiance[cy + dy, cx + dx] == pytest.approx(reference, abs=0.015)
    assert radiance[cy, cx] == pytest.approx(1.0) and radiance[cy - 5:cy + 6, cx - 5:cx + 6].min() < 0.1


def test_infinite_exit_pupil_is_todays_render_bit_for_bit():
    """exit_pupil_distance_mm = inf (argument or camera) renders exactly the telecentric bytes; a finite one differs."""
    cam = camera(pixel_mm=0.25 / 9, f_number=4.0, cfa="RGGB")
    scene = Scene((Plane(600.0, Noise(3.0, seed=2)), Plane(400.0, Uniform(0.7), region_mm=(-5, 5, -5, 5))))
    options = dict(rotation_deg=0.7, offset_px=(0.3, -0.2), shot_noise_photons=1000, seed=3)

    def digest(cap):
        h = hashlib.sha256()
        for a in (cap.raw, cap.white, cap.ideal_views, cap.ideal_weight, cap.plane_label, cap.depth_mm):
            h.update(np.ascontiguousarray(a).tobytes())
        h.update(repr(cap.grid).encode())
        return h.hexdigest()

    base = simulate.render(cam, scene, (90, 120), **options)
    assert base.lens_grid == base.grid and base.options["exit_pupil_distance_mm"] == math.inf
    assert digest(simulate.render(cam, scene, (90, 120), exit_pupil_distance_mm=math.inf, **options)) == digest(base)
    finite = simulate.render(cam, scene, (90, 120), exit_pupil_distance_mm=40.0, **options)
    assert finite.camera.main_optics.exit_pupil_distance_mm == 40.0 and finite.lens_grid != finite.grid
    assert not np.array_equal(finite.white, base.white)
    assert digest(simulate.render(finite.camera, scene, (90, 120), **options)) == digest(finite)  # from the camera
    back = simulate.render(finite.camera, scene, (90, 120), exit_pupil_distance_mm=math.inf, **options)
    assert digest(back) == digest(base)


def test_depth_and_ideal_views_follow_the_tilted_chief_rays():
    """With a finite exit pupil the central view's chief ray leaves lens s with slope −s/d_A: its depth on a tilted
    plane and what the central ideal view sees follow that ray (plain numpy, Eqs. 16-19)."""
    d_a, d, tilt = 40.0, 450.0, (25.0, -10.0)
    cam = camera(pixel_mm=0.25 / 7, f_number=2.0, exit_pupil_distance_mm=d_a)
    shape = (150, 170)
    plane = Plane(d, Uniform(0.5), tilt_deg=tilt)
    cap = simulate.render(cam, Scene((plane,)), shape, rim_radius_mm=None)
    axis = np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2])
    s = (cap.lens_grid.centers_xy_px() - axis) * cam.pixel_pitch_mm
    slope = -s / d_a
    u = s + slope * cam.main_optics.image_distance_mm
    q = slope - u / F_U
    big_l = cam.main_optics.sensor_path_mm(cam.mla_path_mm)
    kx = math.tan(math.radians(tilt[0]))
    ky = math.tan(math.radians(tilt[1])) / math.cos(math.radians(tilt[0]))
    z = (d - big_l - u[..., 0] * kx - u[..., 1] * ky) / (1 + q[..., 0] * kx + q[..., 1] * ky)
    np.testing.assert_allclose(cap.depth_mm, z + big_l, rtol=1e-10)
    u0, q0 = s, -s / F_U  # the telecentric chief ray of the same lenses
    z0 = (d - big_l - u0[..., 0] * kx - u0[..., 1] * ky) / (1 + q0[..., 0] * kx + q0[..., 1] * ky)
    assert np.abs(cap.depth_mm - (z0 + big_l)).max() > 0.5  # the drift matters for the depth truth
    assert np.all(cap.ideal_weight[cam.center_index, cam.center_index] > 0.99)  # the central view is unvignetted


def test_ideal_views_are_pixels_at_the_micro_image_centres():
    """With p_p = k·p_m/m̂ (k the micro image scale) and the lattice aligned, sensor pixels are the ideal samples
    around the drifted micro image centres: radiance = ideal view × weight."""
    d_a = 50.0
    scale = (d_a + F_S) / d_a
    m = 9
    cam = camera(pixel_mm=0.25 * scale / m, f_number=6.0, cfa="RGGB", exit_pupil_distance_mm=d_a, micro_image_px=m)
    shape = (171, 207)  # odd: the axis, and so the central micro image centre, is a pixel centre
    scene = Scene((Plane(900.0, Noise(2.0, seed=5), tint=(0.3, 0.6, 0.9)),), background=0.25)
    options = dict(rim_radius_mm=3.0, pixel_samples=2, aperture_samples=3)
    radiance = simulate.render_radiance(cam, scene, shape, **options)
    views, weight, grid = simulate.render_ideal_views(cam, scene, shape, **options)
    assert grid.pitch_px == pytest.approx(float(m))
    c = cam.center_index
    centers = np.rint(grid.centers_xy_px()).astype(int)
    np.testing.assert_allclose(grid.centers_xy_px(), centers, atol=1e-9)
    for ky in range(m):
        for kx in range(m):
            sensor = radiance[centers[..., 1] + ky - c, centers[..., 0] + kx - c]
            np.testing.assert_allclose(sensor, views[ky, kx] * weight[ky, kx][..., None], atol=2e-6)
    assert 0.05 < weight.mean() < 0.95


def test_auto_rim_with_an_exit_pupil_keeps_the_inscribed_circle_unvignetted():
    for d_a in (30.0, 80.0, 400.0):  # the exit pupil between the main lens and the MLA, and beyond the main lens
        cam = camera(pixel_mm=0.05, f_number=12.0, exit_pupil_distance_mm=d_a)
        shape = (180, 300)
        auto = simulate.render_radiance(cam, None, shape)
        free = simulate.render_radiance(cam, None, shape, rim_radius_mm=None)
        yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
        inside = np.hypot(xx - (shape[1] - 1) / 2, yy - (shape[0] - 1) / 2) <= shape[0] / 2 - 0.5
        np.testing.assert_array_equal(auto[inside], free[inside])
        assert auto[:20, :20].sum() < free[:20, :20].sum()  # and the rim cuts at the corners


def test_exit_pupil_in_scene_files_and_bad_values():
    cam_table = {"sensor": {"pixel_pitch_mm": 0.01}, "mla": {"pitch_mm": 0.1, "focal_length_mm": 0.4},
                 "main_lens": {"focal_length_mm": 50.0, "image_distance_mm": 50.0, "f_number": 4.0}}
    for value, expected in [(45.0, 45.0), (math.inf, math.inf), ("inf", math.inf), ("camera", None)]:
        parsed = parse_scene_dict({"camera": cam_table, "render": {"exit_pupil_distance_mm": value}})
        assert parsed.options.exit_pupil_distance_mm == expected
        assert parsed.options.render_kwargs()["exit_pupil_distance_mm"] == expected
    assert parse_scene_dict({"camera": cam_table}).options.exit_pupil_distance_mm is None
    assert "exit_pupil_distance_mm" not in parse_scene_dict({"camera": cam_table}).options.to_json_dict()
    for bad in (0.0, -3.0, "far", True):
        with pytest.raises(LfprocError, match="exit_pupil_distance_mm"):
            parse_scene_dict({"camera": cam_table, "render": {"exit_pupil_distance_mm": bad}})
    with pytest.raises(LfprocError, match="exit_pupil_distance_mm"):
        simulate.render_white(camera(), (100, 100), exit_pupil_distance_mm=-1.0)


# ---------------------------------------------------------------------------- against PlenoptiSign (Hahne et al. 2018)
def shifted_view_variance(views, a, border):
    """Variance across the views shifted by the contract's a·(c − k) lenses (bilinear, plain numpy): (Ny, Nx)."""
    return np.var(shifted_views(views, a), axis=0)[border:-border, border:-border]


def plenoptisign_distance_mm(a, d_a, m_hat, focus_mm=math.inf):
    """PlenoptiSign 1.1.3's refocusing distance of slice a, converted to lfproc's convention (from the sensor).

    Its pixel pitch is the sample pitch of a view inside a micro image, here the micro image pitch over m̂
    (k·p_m/m̂, k = (d_A + f_s)/d_A), as the simulator's ideal views sample it. Its distance counts from the micro
    lens array, so f_s + H1sH2s is added.
    """
    from plenoptisign import MainClass

    scale = 1.0 if math.isinf(d_a) else (d_a + F_S) / d_a
    model = MainClass()
    model.pp, model.fs, model.hh, model.pm, model.dA = 0.25 * scale / m_hat, F_S, H_S, 0.25, d_a
    model.fU, model.HH, model.df, model.f_num, model.a, model.M = F_U, H_U, focus_mm, 4.0, a, m_hat
    model.refo()
    return model.d + F_S + H_S


@pytest.mark.parametrize("d_a", [200.0, 60.0])
def test_sharpest_refocus_with_an_exit_pupil_matches_plenoptisign(d_a):
    """The ideal views of a plane, rendered with a finite exit pupil, agree best across views at the a whose
    refocusing distance PlenoptiSign (the exit pupil model of Hahne et al. 2018) puts at the plane, not at the
    telecentric a = 1.5 of the same plane."""
    from scipy.optimize import brentq

    cam = Camera(0.25 / 9, 0.25, F_S, MainLens(F_U, F_U, principal_plane_gap_mm=H_U, f_number=4.0, exit_pupil_distance_mm=d_a), mla_principal_plane_gap_mm=H_S, micro_image_px=9)
    d = geometry.slice_distance_mm(cam.with_optics(replace(cam.main_optics, exit_pupil_distance_mm=math.inf)), 1.5)  # telecentric a = 1.5
    assert plenoptisign_distance_mm(1.5, math.inf, 9) == pytest.approx(d, rel=1e-9)  # the two conventions agree
    a_expected = brentq(lambda a: plenoptisign_distance_mm(a, d_a, 9) - d, 0.3, 1.49)
    views, weight, grid = simulate.render_ideal_views(cam, Scene((Plane(d, Noise(1.5, seed=4)),)), (420, 420),
                                                       rim_radius_mm=None)
    assert weight.min() > 0.99
    a_grid = np.round(np.arange(a_expected - 0.3, a_expected + 0.3001, 0.02), 6)
    consistency = np.array([-shifted_view_variance(views, a, border=8).mean() for a in a_grid])
    k = int(np.clip(np.argmax(consistency), 1, len(a_grid) - 2))
    y0, y1, y2 = consistency[k - 1:k + 2]
    peak = a_grid[k] + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * 0.02
    assert 0 < k < len(a_grid) - 1  # a true maximum inside the sweep
    # 0.02: the bilinear shift-and-sum measurement's own bias on telecentric renders (see test_simulate.py)
    assert peak == pytest.approx(a_expected, abs=0.02)
    assert abs(a_expected - 1.5) > 0.2  # the telecentric model would miss this plane by far more
    # and lfproc's geometry with the same exit pupil maps the plane to the same a (the seam calibration and
    # decoding rely on: ideal views sample the micro images at k·p_m/m̂ as the geometry assumes)
    assert geometry.refocus_parameter(cam, d) == pytest.approx(a_expected, abs=1e-6)
