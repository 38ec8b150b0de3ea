"""The forward renderer against independent references: plain-numpy ray formulas, geometry closed forms,
Monte Carlo aperture fractions and known noise statistics. Sensors are small so the file runs in seconds."""

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from focus import focused
from lfproc import geometry, simulate
from lfproc.camera import Camera, MainLens
from lfproc.errors import LfprocError
from lfproc.grid import LensGrid
from lfproc.simulate import (Checkerboard, ImageTexture, Noise, Plane, Scene, Sinusoid, Uniform, load_scene_file,
                          parse_scene_dict)

from conftest import ROOT, assert_clean_error, run_cli
from plainref import shifted_views

F_U, H_U, F_S, H_S = 99.5145, -33.184, 2.749, 0.374  # the paper's f100 main lens and micro lens


def camera(m=9, pixel_mm=None, grid="rectangular", f_number=4.0, focus_mm=math.inf, cfa="none", **kw):
    """The paper's camera scaled down to m̂ = m px per micro lens (p_m = 0.25 mm)."""
    cam = Camera(pixel_mm or 0.25 / m, 0.25, F_S, MainLens(F_U, F_U, principal_plane_gap_mm=H_U, f_number=f_number), mla_principal_plane_gap_mm=H_S, grid=grid, cfa=cfa, **kw)
    return cam if math.isinf(focus_mm) else focused(cam, focus_mm)


# ---------------------------------------------------------------------------- plain-numpy references
def parabola_peak(x, y):
    k = int(np.clip(np.argmax(y), 1, len(y) - 2))
    y0, y1, y2 = y[k - 1], y[k], y[k + 1]
    return x[k] + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * (x[1] - x[0])


def chief_ray_plane_xy(cam, grid, shape, distance_mm):
    """Eqs. 13-19 in numpy: where the chief ray of each ideal view sample meets the plane, in plane coordinates."""
    m, c = cam.m_hat, cam.center_index
    axis = np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2])
    s = (grid.centers_xy_px() - axis) * cam.pixel_pitch_mm  # (rows, cols, 2) mm
    u, v = grid.axes
    k = np.arange(m) - c
    off = (k[None, :, None] * u + k[:, None, None] * v) * cam.effective_pixel_pitch_mm  # (ky, kx, 2)
    x = s[None, None] + off[:, :, None, None]
    slope = (s[None, None] - x) / cam.mla_focal_length_mm  # Eq. 13
    at_lens = s[None, None] + slope * cam.main_optics.image_distance_mm  # Eq. 16 (chief ray: t = s)
    q = (slope * cam.main_optics.focal_length_mm - at_lens) / cam.main_optics.focal_length_mm  # Eqs. 17-18
    hit = at_lens + q * (distance_mm - cam.main_optics.sensor_path_mm(cam.mla_path_mm))  # Eq. 19
    return -hit  # plane coordinates are "as seen in the capture" (inverted heights)


# ---------------------------------------------------------------------------- optics against the geometry
@pytest.mark.parametrize("focus_mm, target", [(math.inf, ("a", 1)), (math.inf, ("d", 360.0)),
                                              (1500.0, ("a", 2))])
def test_refocus_is_sharpest_at_the_geometry_parameter(focus_mm, target):
    """Shift-and-sum of the ideal views is sharpest at refocus_parameter(d) (Eq. 21 inverted)."""
    cam = camera(m=9, focus_mm=focus_mm)
    d = geometry.slice_distance_mm(cam, target[1]) if target[0] == "a" else target[1]
    a_true = geometry.refocus_parameter(cam, d)
    z = d - cam.main_optics.sensor_path_mm(cam.mla_path_mm)
    lens_on_plane = 0.25 * abs(1 - z / F_U)  # mm of plane per lens, central view
    views, weight, grid = simulate.render_ideal_views(cam, Scene((Plane(d, Noise(2.0 * lens_on_plane, seed=1)),)),
                                                       (400, 400), rim_radius_mm=None)
    assert weight.min() > 0.99  # f/4: every view lies inside the stop
    border = 14  # > max |a|·c lenses: every crop sample has all views inside the array
    a_grid = np.round(np.arange(a_true - 0.3, a_true + 0.3001, 0.02), 6)
    # cross-view agreement (minus the mean variance across views): all views see the same point at a = a_true
    consistency = [-shifted_views(views, a)[:, border:-border, border:-border].var(axis=0).mean() for a in a_grid]
    # Tolerance 0.02 in a: the slice's own depth of field spans about ±1/(2c) = ±0.125 in a, and linear
    # interpolation between lenses biases the peak by < 0.01 in this set-up.
    assert parabola_peak(a_grid, np.array(consistency)) == pytest.approx(a_true, abs=0.02)
    if target[0] == "a":  # integer slices: the plain integer shift-and-sum has the most gradient energy there
        energies = {}
        for a in range(target[1] - 2, target[1] + 3):
            img = shifted_views(views, float(a)).mean(axis=0)[border:-border, border:-border]
            energies[a] = (np.diff(img, axis=0) ** 2).mean() + (np.diff(img, axis=1) ** 2).mean()
        assert max(energies, key=energies.get) == target[1]


@pytest.mark.parametrize("kind, rotation, focus_mm", [("rectangular", 0.0, math.inf), ("hexagonal", 3.0, 800.0)])
def test_ideal_views_follow_the_chief_rays(kind, rotation, focus_mm):
    """A low-frequency grating: each ideal view sample equals the texture where its chief ray meets the plane."""
    cam = camera(m=7, grid=kind, focus_mm=focus_mm, f_number=2.0)
    shape, d = (150, 170), 450.0
    grating = Sinusoid(period_mm=30.0, angle_deg=30.0, phase_deg=20.0, low=0.1, high=0.9)
    views, weight, grid = simulate.render_ideal_views(cam, Scene((Plane(d, grating, center_mm=(1.0, -2.0)),)), shape,
                                                       rotation_deg=rotation, offset_px=(0.3, -0.4),
                                                       rim_radius_mm=None)
    xy = chief_ray_plane_xy(cam, grid, shape, d) - np.array([1.0, -2.0])
    phase = 2 * np.pi * (xy[..., 0] * np.cos(np.radians(30)) + xy[..., 1] * np.sin(np.radians(30))) / 30.0
    expected = 0.1 + 0.8 * (0.5 + 0.5 * np.cos(phase + np.radians(20)))
    # integration over the effective pixel and the lens aperture blurs by < 1 mm of a 30 mm period: < 0.005
    np.testing.assert_allclose(views[..., 0], expected, atol=0.005)
    assert np.all(weight == 1.0)


def test_sensor_pixels_equal_ideal_views_times_weight_when_pixels_are_effective_pixels():
    """With p_p = p_m/m̂, no rotation and lens centres on pixel centres, the renderer's sensor pixels ARE the ideal
    samples: raw radiance = ideal radiance × passing fraction, for every view of every lens (CFA scene, vignetted)."""
    cam = camera(m=9, f_number=6.0, cfa="RGGB")
    shape = (171, 207)  # odd: the axis, and so a lens centre, is a pixel centre
    scene = Scene((Plane(420.0, Checkerboard(1.7), region_mm=(-3.0, 9.0, -8.0, 2.0), tint=(1.0, 0.5, 0.2)),
                   Plane(900.0, Noise(2.0, seed=5), tint=(0.3, 0.6, 0.9))), background=0.25)
    options = dict(rim_radius_mm=3.0, pixel_samples=2, aperture_samples=3)  # a strong rim: many weights < 1
    radiance = simulate.render_radiance(cam, scene, shape, **options)
    views, weight, grid = simulate.render_ideal_views(cam, scene, shape, **options)
    assert grid.origin_xy_px[0] == int(grid.origin_xy_px[0]) and grid.pitch_px == pytest.approx(9.0)
    c = cam.center_index
    centers = np.rint(grid.centers_xy_px()).astype(int)
    for ky in range(9):
        for kx in range(9):
            sensor = radiance[centers[..., 1] + ky - c, centers[..., 0] + kx - c]  # (rows, cols, 3)
            np.testing.assert_allclose(sensor, views[ky, kx] * weight[ky, kx][..., None], atol=2e-6)
    assert 0.05 < weight.mean() < 0.95 and weight.min() == 0.0


def test_plane_labels_name_the_nearest_plane_on_the_central_chief_ray():
    cam = camera(m=7)
    shape, near, far = (140, 140), 400.0, 700.0
    scene = Scene((Plane(far, Uniform(0.3), name="far"), Plane(near, Uniform(0.9), region_mm=(0.0, 50, -50, 50))))
    cap = simulate.render(cam, scene, shape, ideal_views=True)
    x_near = chief_ray_plane_xy(cam, cap.grid, shape, near)[cam.center_index, cam.center_index]
    expected = np.where(x_near[..., 0] >= 0.0, 1, 0)
    np.testing.assert_array_equal(cap.plane_label, expected)
    assert set(np.unique(expected)) == {0, 1}
    c = cam.center_index
    clear = x_near[..., 0] >= 1.5  # beyond the ~1 mm footprint of an ideal sample's rays on the near plane
    assert clear.sum() > 10
    np.testing.assert_allclose(cap.ideal_views[c, c, ..., 0][clear], 0.9, atol=1e-6)
    assert cap.planes == scene.planes


# ---------------------------------------------------------------------------- white image
@pytest.mark.parametrize("kind, rotation", [("rectangular", 1.7), ("hexagonal", -2.3)])
def test_white_micro_image_centroids_sit_on_the_lens_centres(kind, rotation):
    """Telecentric: every micro image is centred under its lens (9 µm pixels, 250 µm lenses: 27.78 px pitch)."""
    cam = camera(pixel_mm=0.009, grid=kind, f_number=13.0)  # disk radius f_s/2N = 11.7 px < half pitch 13.9 px
    white, grid = simulate.render_white(cam, (200, 230), rotation_deg=rotation, offset_px=(0.37, -0.21),
                                        rim_radius_mm=None, pixel_samples=4)
    assert grid.kind == kind and grid.pitch_px == pytest.approx(250 / 9)
    yy, xx = np.mgrid[0:white.shape[0], 0:white.shape[1]]
    radius_px = F_S / 26.0 / 0.009
    errors = []
    for cx, cy in grid.centers_xy_px().reshape(-1, 2):
        window = (xx - cx) ** 2 + (yy - cy) ** 2 <= (radius_px + 2) ** 2
        w = white[window].astype(np.float64)
        errors.append(math.hypot((w * xx[window]).sum() / w.sum() - cx, (w * yy[window]).sum() / w.sum() - cy))
        assert w.sum() / (0.8 * 65535) == pytest.approx(math.pi * radius_px ** 2, rel=0.01)  # the disk's area
    assert len(errors) >= 20 and max(errors) < 0.02


def test_vignetting_matches_a_monte_carlo_aperture_fraction():
    """Per-lens white sums equal the fraction of (sensor point, aperture point) pairs that pass stop and rim."""
    cam = camera(m=11, f_number=7.0)
    shape, rim = (165, 231), 6.0  # 15 × 21 lenses whose cells are exact 11 × 11 pixel blocks
    white, grid = simulate.render_white(cam, shape, rim_radius_mm=rim, aperture_samples=6)
    assert (grid.rows, grid.cols) == (15, 21)
    rng = np.random.default_rng(1)
    n = 100_000
    axis = np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2])
    measured, reference = [], []
    for row, col in [(7, 10), (0, 0), (0, 10), (7, 0), (14, 20), (3, 5), (11, 17), (14, 3)]:
        s = (grid.lens_xy(row, col) - axis) * cam.pixel_pitch_mm
        x = s + rng.uniform(-0.125, 0.125, (n, 2))  # sensor point in the cell
        t = s + rng.uniform(-0.125, 0.125, (n, 2))  # micro lens aperture point
        slope = (s - x) / F_S
        at_lens = t + slope * cam.main_optics.image_distance_mm
        passes = (np.hypot(*slope.T) <= 1 / (2 * 7.0)) & (np.hypot(*at_lens.T) <= rim)
        reference.append(passes.mean())
        cx, cy = np.rint(grid.lens_xy(row, col)).astype(int)
        measured.append(white[cy - 5:cy + 6, cx - 5:cx + 6].astype(np.float64).sum() / (121 * 0.8 * 65535))
    # MC σ ≤ 0.0016; the renderer's 2×2 pixel × 6×6 aperture strata err by up to ≈ 0.005 where the rim cuts
    np.testing.assert_allclose(measured, reference, atol=0.007)
    assert measured[0] == max(measured) and reference[0] > 0.97  # the centre is (almost) clear of the rim ...
    assert max(measured[1], measured[4]) < 0.8 * measured[0]  # ... which visibly darkens the corners


def test_auto_rim_keeps_the_inscribed_circle_unvignetted_and_darkens_the_corners():
    cam = camera(m=5, f_number=12.0)
    shape = (180, 300)
    auto = simulate.render_radiance(cam, None, shape)
    free = simulate.render_radiance(cam, None, shape, rim_radius_mm=None)
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    radius = np.hypot(xx - (shape[1] - 1) / 2, yy - (shape[0] - 1) / 2)
    inside = radius <= shape[0] / 2 - 0.5
    np.testing.assert_array_equal(auto[inside], free[inside])
    assert auto[:20, :20].sum() < 0.9 * free[:20, :20].sum()
    assert simulate.auto_rim_radius_mm(cam, shape) == pytest.approx(
        90 * 0.05 + 0.25 / math.sqrt(2) + (F_S + F_U) * min(1 / 24, 0.25 / math.sqrt(2) / F_S))


@pytest.mark.parametrize("kind", ["rectangular", "hexagonal"])
def test_aperture_samples_fill_the_lens_cell_uniformly(kind):
    """Stratified aperture points: inside the cell, centred, with the cell's second moment (area-uniform)."""
    pitch, rotation = 0.25, 20.0
    pts = simulate.aperture_offsets_mm(kind, pitch, rotation, 8)
    assert len(pts) == (64 if kind == "rectangular" else 3 * 64)
    t = math.radians(rotation)
    local = pts @ np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])  # back to (u, v)
    normals = [0.0, 90.0] if kind == "rectangular" else [0.0, 60.0, 120.0]  # the cell's face directions
    for angle in normals:
        n = np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle))])
        assert np.abs(local @ n).max() < pitch / 2
    np.testing.assert_allclose(local.mean(axis=0), 0.0, atol=1e-12)
    # second moment per axis: p²/12 for the square, 5a²/24 (side a = p/√3) for the regular hexagon
    expected = pitch ** 2 / 12 if kind == "rectangular" else 5 * (pitch / math.sqrt(3)) ** 2 / 24
    np.testing.assert_allclose((local ** 2).mean(axis=0), expected, rtol=0.02)


def test_default_grid_covers_the_sensor_with_complete_lenses_and_includes_the_anchor():
    for kind, rotation, offset in [("rectangular", 0.0, (0.0, 0.0)), ("rectangular", 4.0, (3.2, -1.1)),
                                   ("hexagonal", -1.0, (0.5, 0.25))]:
        cam = camera(pixel_mm=0.009, grid=kind)
        shape = (300, 420)
        grid = simulate.default_grid(cam, shape, rotation, offset)
        xy = grid.centers_xy_px()
        half = grid.pitch_px / 2
        assert xy[..., 0].min() >= half - 0.5 and xy[..., 0].max() <= shape[1] - 0.5 - half
        assert xy[..., 1].min() >= half - 0.5 and xy[..., 1].max() <= shape[0] - 0.5 - half
        anchor = np.array([(shape[1] - 1) / 2 + offset[0], (shape[0] - 1) / 2 + offset[1]])
        assert np.min(np.hypot(*(xy - anchor).reshape(-1, 2).T)) < 1e-9
        # nearly as many lenses as fit: the sensor area minus the half-pitch margin, over the cell area
        cell = grid.pitch_px * grid.row_spacing_px
        fit = (shape[0] - grid.pitch_px) * (shape[1] - grid.pitch_px) / cell
        assert grid.rows * grid.cols >= 0.75 * fit


# ---------------------------------------------------------------------------- sensor model: CFA, levels, noise
@pytest.mark.parametrize("cfa", ["RGGB", "BGGR", "GRBG", "GBRG"])
def test_cfa_mosaic_keeps_each_pixels_colour(cfa):
    cam = camera(m=7, cfa=cfa, f_number=5.0)
    tint = {"R": 0.2, "G": 0.5, "B": 0.9}
    shape = (70, 84)
    cap = simulate.render(cam, Scene((), background=(tint["R"], tint["G"], tint["B"])), shape, ideal_views=False)
    lit = simulate.render_radiance(cam, None, shape)[:, :, 0].astype(np.float64)  # radiance-1 white
    for k, colour in enumerate(cfa):
        dy, dx = divmod(k, 2)
        expected = np.rint(0.8 * 65535 * tint[colour] * lit[dy::2, dx::2])
        assert np.abs(cap.raw[dy::2, dx::2] - expected).max() <= 1
    assert cap.raw.dtype == np.uint16 and cap.raw.shape == shape


def test_mono_camera_sees_luminance_and_mosaic_is_exact():
    rgb = np.random.default_rng(0).random((4, 6, 3)).astype(np.float32)
    np.testing.assert_allclose(simulate.mosaic(rgb, "none"), rgb @ np.array([0.2126, 0.7152, 0.0722]), rtol=1e-6)
    raw = simulate.mosaic(rgb, "GBRG")
    assert raw[0, 0] == rgb[0, 0, 1] and raw[0, 1] == rgb[0, 1, 2] and raw[1, 0] == rgb[1, 0, 0]
    assert raw[1, 1] == rgb[1, 1, 1] and raw[3, 5] == rgb[3, 5, 1]


def test_mono_kernels_weight_a_coloured_scene_by_rec709_luminance():
    """channels=1 inside both kernels is the Rec. 709 luminance of what channels=3 renders."""
    rec709 = np.array([0.2126, 0.7152, 0.0722])     # the standard's numbers, not the module's tuple
    assert simulate.LUMA_WEIGHTS == tuple(rec709)
    cam, scene, shape = camera(m=5, f_number=2.0), Scene((), background=(0.9, 0.1, 0.4)), (40, 50)
    rgb = simulate.render_radiance(cam, scene, shape, channels=3).astype(np.float64)
    mono = simulate.render_radiance(cam, scene, shape, channels=1)
    assert rgb[..., 0].max() > 0.5 > rgb[..., 1].max()      # really coloured
    np.testing.assert_allclose(mono[..., 0], rgb @ rec709, rtol=1e-6, atol=1e-7)
    views_rgb, weight_rgb, _ = simulate.render_ideal_views(cam, scene, shape, channels=3)
    views_mono, weight_mono, _ = simulate.render_ideal_views(cam, scene, shape, channels=1)
    np.testing.assert_array_equal(weight_mono, weight_rgb)
    np.testing.assert_allclose(views_mono[..., 0], views_rgb.astype(np.float64) @ rec709, rtol=1e-6)
    np.testing.assert_allclose(views_mono, 0.9 * 0.2126 + 0.1 * 0.7152 + 0.4 * 0.0722, rtol=1e-6)


@pytest.mark.parametrize("channels", [0, 2, 4, -1, 1.0, True, "3"])
def test_bad_channels_are_user_errors(channels):
    cam = camera(m=5, f_number=2.0)
    for render in (simulate.render_ideal_views, simulate.render_radiance):
        with pytest.raises(LfprocError, match="channels must be 1"):
            render(cam, Scene(), (40, 50), channels=channels)


@pytest.mark.parametrize("scene", [None, "scene.toml", (), 0.5])
def test_ideal_views_need_a_scene(scene):
    with pytest.raises(LfprocError, match="scene must be an lfproc.simulate.Scene"):
        simulate.render_ideal_views(camera(m=5, f_number=2.0), scene, (40, 50))
    if scene is not None:  # render_radiance documents None as the white image
        with pytest.raises(LfprocError, match="scene must be an lfproc.simulate.Scene"):
            simulate.render_radiance(camera(m=5, f_number=2.0), scene, (40, 50))


def test_shot_noise_photons_beyond_the_limit_are_user_errors():
    cam = camera(m=7, f_number=2.0)
    for photons in (1e20, simulate.MAX_SHOT_NOISE_PHOTONS * 1.01, 0, 0.0, -5.0, float("nan")):
        with pytest.raises(LfprocError, match="shot_noise_photons"):
            simulate.render_white(cam, (50, 60), shot_noise_photons=photons)
        with pytest.raises(LfprocError, match="shot_noise_photons"):
            simulate.radiance_to_dn(np.ones((2, 2)), cam, shot_noise_photons=photons)
    # at the limit the noise is far below one DN, and very bright values still sample (lam clipped)
    dn = simulate.radiance_to_dn(np.array([[0.5, 1e9]]), cam, exposure=1.0,
                                 shot_noise_photons=simulate.MAX_SHOT_NOISE_PHOTONS)
    assert dn.tolist() == [[round(0.5 * 65535), 65535]]


def test_16_bit_levels_clip_at_black_and_white():
    cam = camera(m=7, f_number=12.0, black_level=64.0, white_level=4095.0)
    scene = Scene((Plane(500.0, Uniform(1.0), region_mm=(0.0, 100.0, -100.0, 100.0)),), background=0.3)
    cap = simulate.render(cam, scene, (70, 84), exposure=1.5, ideal_views=False)
    assert cap.raw.max() == 4095 and cap.raw.min() == 64  # saturated plane; dark corners between micro images
    lit = simulate.render_radiance(cam, scene, (70, 84))[:, :, 0]
    unsaturated = (lit > 0) & (lit * 1.5 < 0.99)
    np.testing.assert_array_equal(cap.raw[unsaturated], np.rint(64 + 4031 * 1.5 * lit[unsaturated].astype(float)))
    cap16 = simulate.render(camera(m=7, f_number=12.0), scene, (70, 84), exposure=3.0, read_noise_dn=50.0,
                            ideal_views=False)
    assert cap16.raw.max() == 65535 and cap16.raw.min() == 0


def test_same_seed_same_bytes_other_seed_other_noise_with_the_expected_statistics():
    cam = camera(m=7, f_number=2.0)
    scene = Scene((), background=0.5)
    kw = dict(shot_noise_photons=2000.0, read_noise_dn=20.0, ideal_views=False, rim_radius_mm=None)
    first = simulate.render(cam, scene, (98, 112), seed=3, **kw)
    again = simulate.render(cam, scene, (98, 112), seed=3, **kw)
    other = simulate.render(cam, scene, (98, 112), seed=4, **kw)
    assert first.raw.tobytes() == again.raw.tobytes() and first.white.tobytes() == again.white.tobytes()
    assert first.raw.tobytes() != other.raw.tobytes() and first.white.tobytes() != other.white.tobytes()
    noiseless = simulate.render(cam, scene, (98, 112), ideal_views=False, rim_radius_mm=None).raw.astype(float)
    assert np.all(noiseless == np.rint(0.8 * 0.5 * 65535))  # f/2: every pixel fully lit
    residual = first.raw.astype(float) - noiseless
    expected_var = 65535.0 ** 2 * 0.4 / 2000.0 + 20.0 ** 2  # Poisson in photons at full scale, plus read noise
    assert abs(residual.mean()) < 5 * math.sqrt(expected_var / residual.size)
    assert residual.var() == pytest.approx(expected_var, rel=0.06)
    white, _ = simulate.render_white(cam, (98, 112), seed=3, **{k: kw[k] for k in kw if k != "ideal_views"})
    assert white.tobytes() == first.white.tobytes()


# ---------------------------------------------------------------------------- textures
def test_texture_orientation_checkerboard_and_image_are_upright_in_the_central_view():
    """Plane coordinates are 'as seen in the capture': x with the column, y with the row of the central view."""
    cam = camera(m=5, f_number=2.0)
    pixels = np.zeros((40, 40, 3), np.float32)
    pixels[:20, 20:] = 1.0  # top-right quadrant of the image is white
    d = 600.0  # the sensor sees about ±17 × ±13 mm of the plane: all inside the 40 mm image
    scene = Scene((Plane(d, ImageTexture(pixels, width_mm=40.0)),), background=0.5)
    cap = simulate.render(cam, scene, (120, 160), rim_radius_mm=None)
    central = cap.ideal_views[2, 2, :, :, 0]
    rows, cols = central.shape
    assert central[: rows // 3, -cols // 3:].mean() > 0.9 and central[: rows // 3, : cols // 3].mean() < 0.1
    assert central[-rows // 3:, -cols // 3:].mean() < 0.1
    # checkerboard: the square at 0 <= x, y < period/2 is `low`; evaluated at chief-ray points far from edges
    xy = chief_ray_plane_xy(cam, cap.grid, (120, 160), d)[2, 2]
    board = simulate.render(cam, Scene((Plane(d, Checkerboard(40.0, low=0.2, high=0.7)),)), (120, 160),
                            rim_radius_mm=None).ideal_views[2, 2, :, :, 0]
    cell = np.floor(xy / 20.0).astype(int)
    expected = np.where((cell[..., 0] + cell[..., 1]) % 2 == 0, 0.2, 0.7)
    far_from_edges = np.min(np.abs(xy / 20.0 - np.rint(xy / 20.0)), axis=-1) > 0.1
    np.testing.assert_allclose(board[far_from_edges], expected[far_from_edges], atol=1e-6)
    assert far_from_edges.sum() > 0.5 * far_from_edges.size


@pytest.mark.parametrize("channels", ["RGB", "RGBA"])
def test_image_texture_file_keeps_its_colour(tmp_path, channels):
    """A pure-red PNG read through the scene file renders red: G = B = 0 in the ideal views."""
    import OpenImageIO as oiio

    pixels = np.zeros((8, 12, len(channels)), np.uint8)
    pixels[..., 0] = 255
    if channels == "RGBA":
        pixels[..., 3] = 255
    out = oiio.ImageOutput.create(str(tmp_path / "red.png"))
    assert out.open(str(tmp_path / "red.png"), oiio.ImageSpec(12, 8, len(channels), oiio.UINT8))
    assert out.write_image(pixels)
    out.close()
    texture_pixels = __import__("lfproc.simulate", fromlist=["x"]).read_texture_image(str(tmp_path / "red.png"))
    np.testing.assert_array_equal(texture_pixels, np.broadcast_to([1.0, 0.0, 0.0], (8, 12, 3)))
    parsed = parse_scene_dict({"camera": str(ROOT / "samples" / "cameras" / "paper-f100.toml"), "background": 0.5,
                               "plane": [{"distance_mm": 600.0, "texture": "image", "path": "red.png",
                                          "width_mm": 60.0}]}, base_dir=str(tmp_path))
    cam = camera(m=5, f_number=2.0)
    views, _, _ = simulate.render_ideal_views(cam, parsed.scene, (120, 160), rim_radius_mm=None, channels=3)
    assert views[..., 0].min() > 0.99        # everything the sensor sees lies inside the 60 mm image
    assert views[..., 1].max() == 0.0 and views[..., 2].max() == 0.0


def test_scene_file_shot_noise_zero_is_an_error_and_none_is_off(tmp_path):
    cam = f"camera = '{ROOT / 'samples' / 'cameras' / 'paper-f100.toml'}'"
    for value, expected in (("0", None), ("0.0", None), ("false", "off"), ("'none'", "off"), ("'off'", "off"),
                            ("100", 100.0)):
        (tmp_path / "scene.toml").write_text(f"{cam}\n[render]\nshot_noise_photons = {value}\n")
        if expected is None:
            with pytest.raises(LfprocError, match="shot_noise_photons"):
                load_scene_file(tmp_path / "scene.toml")
        else:
            photons = load_scene_file(tmp_path / "scene.toml").options.shot_noise_photons
            assert photons == (None if expected == "off" else expected)


def test_noise_texture_is_deterministic_bounded_and_smooth():
    cam = camera(m=5, f_number=2.0)
    render = lambda seed: simulate.render(cam, Scene((Plane(700.0, Noise(3.0, seed=seed, low=0.1, high=0.6)),)),
                                          (120, 160), rim_radius_mm=None).ideal_views[2, 2, :, :, 0]
    a, b, c = render(1), render(1), render(2)
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - c).mean() > 0.02
    assert a.min() >= 0.1 and a.max() <= 0.6 and a.std() > 0.02
    # band-limited: the feature (3 mm) spans several lenses (~1.5 mm of plane each), so neighbours correlate
    centred = a - a.mean()
    assert (centred[:, 1:] * centred[:, :-1]).mean() > 0.3 * centred.var()


# ---------------------------------------------------------------------------- scene files and the CLI
SCENE = """
camera = "{camera}"
background = 0.05
[render]
height_px = 60
width_px = 90
rotation_deg = 1.0
offset_px = [0.2, -0.3]
shot_noise_photons = 3000
read_noise_dn = 2.0
seed = 5
[[plane]]
name = "card"
distance_mm = 313.066
texture = "checkerboard"
period_mm = 2.0
region_mm = [-1.0, 5.0, -30.0, 30.0]
tint = [1.0, 0.5, 0.25]
[[plane]]
name = "wall"
distance_mm = 1000.0
texture = "noise"
feature_mm = 3.0
"""


def test_cli_writes_the_capture_and_ground_truth(tmp_path):
    import OpenImageIO as oiio

    cam_path = ROOT / "samples" / "cameras" / "paper-f100.toml"
    (tmp_path / "scene.toml").write_text(SCENE.format(camera=cam_path))
    proc = run_cli("simulate", tmp_path / "scene.toml", "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    parsed = load_scene_file(tmp_path / "scene.toml")
    expected = simulate.render(parsed.camera, parsed.scene, parsed.options.sensor_shape,
                               **parsed.options.render_kwargs())
    for name, array in [("capture.png", expected.raw), ("white.png", expected.white)]:
        buf = oiio.ImageBuf(str(tmp_path / "out" / name))
        assert buf.spec().format == oiio.UINT16
        np.testing.assert_array_equal(buf.get_pixels(oiio.UINT16)[:, :, 0], array)
    truth = json.loads((tmp_path / "out" / "ground_truth.json").read_text())
    assert LensGrid.from_json_dict(truth["grid"]) == expected.grid
    assert [p["refocus_a"] for p in truth["planes"]] == pytest.approx(
        [geometry.refocus_parameter(parsed.camera, 313.066), geometry.refocus_parameter(parsed.camera, 1000.0)])
    assert truth["planes"][0]["refocus_a"] == pytest.approx(1.0, abs=1e-4)  # the paper's Table 2, a = 1
    npz = np.load(tmp_path / "out" / "ground_truth.npz")
    np.testing.assert_array_equal(npz["ideal_views"], expected.ideal_views)
    np.testing.assert_array_equal(npz["plane_label"], expected.plane_label)
    assert Camera.from_toml(tmp_path / "out" / "camera.toml") == parsed.camera


def test_documented_example_scene_parses(tmp_path):
    text = (ROOT / "docs" / "scene-format.md").read_text()
    example = text.split("```toml", 1)[1].split("```", 1)[0]
    cams = tmp_path / "cameras"
    cams.mkdir()
    (cams / "paper-f100.toml").write_text((ROOT / "samples" / "cameras" / "paper-f100.toml").read_text())
    (tmp_path / "scene.toml").write_text(example)
    parsed = load_scene_file(tmp_path / "scene.toml")
    assert len(parsed.scene.planes) >= 3 and parsed.camera.main_optics.f_number is not None


BAD_SCENES = [
    ("camera = 'x.toml'\n[[plane]]\ndistance_mm = 1\n", "camera file not found"),
    ("background = 0.1\n", "missing 'camera'"),
    ("{cam}\n[render]\nwidth = 100\n", "unknown key"),
    ("{cam}\n[[plane]]\ndistance_mm = 500\ntexture = 'zebra'\n", "texture must be one of"),
    ("{cam}\n[[plane]]\ndistance_mm = 500\ntexture = 'checkerboard'\nperiod_mm = -1\n", "period_mm"),
    ("{cam}\n[[plane]]\ntexture = 'noise'\nfeature_mm = 1\n", "missing distance_mm"),
    ("{cam}\n[[plane]]\ndistance_mm = 500\ntexture = 'noise'\nfeature_mm = 1\nregion_mm = [1, 0, 0, 1]\n", "x0 < x1"),
    ("{cam}\n[[plane]]\ndistance_mm = 500\ntexture = 'image'\npath = 'nope.png'\nwidth_mm = 5\n", "not found"),
    ("{cam}\n[render]\npixel_samples = 0\n", "pixel_samples"),
    ("{cam}\n[[plane\n", "not valid TOML"),
]


@pytest.mark.parametrize("text, message", BAD_SCENES)
def test_bad_scene_files_raise_lfproc_error(tmp_path, text, message):
    cam = f"camera = '{ROOT / 'samples' / 'cameras' / 'paper-f100.toml'}'"
    (tmp_path / "scene.toml").write_text(text.format(cam=cam))
    with pytest.raises(LfprocError, match=message):
        load_scene_file(tmp_path / "scene.toml")


def test_render_rejects_impossible_setups():
    no_stop = camera(m=7).with_optics(replace(camera(m=7).main_optics, f_number=None))
    with pytest.raises(LfprocError, match="f_number"):
        simulate.render(no_stop, Scene(), (50, 50))
    with pytest.raises(LfprocError, match="not in front of the main lens"):
        simulate.render(camera(m=7), Scene((Plane(50.0, Uniform()),)), (50, 50))
    with pytest.raises(LfprocError, match="no complete micro lens"):
        simulate.render_white(camera(m=7), (5, 5))
    with pytest.raises(LfprocError, match="rim_radius_mm"):
        simulate.render_white(camera(m=7), (50, 50), rim_radius_mm=-1.0)
    inline = parse_scene_dict({"camera": {"sensor": {"pixel_pitch_mm": 0.01}, "mla": {"pitch_mm": 0.25,
                               "focal_length_mm": 2.749}, "main_lens": {"focal_length_mm": 100.0,
                               "image_distance_mm": 100.0}}})
    with pytest.raises(LfprocError, match="f_number"):
        simulate.render(inline.camera, inline.scene, (50, 50))


def test_cli_bad_scene_exits_2_and_writes_nothing(tmp_path):
    (tmp_path / "scene.toml").write_text("camera = 'missing.toml'\n")
    proc = run_cli("simulate", tmp_path / "scene.toml", "-o", tmp_path / "out")
    assert_clean_error(proc, "missing.toml")
    assert not (tmp_path / "out").exists()
