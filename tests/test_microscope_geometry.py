"""Microscope geometry against independent references: a plain ray trace through objective and tube lens,
the sine condition traced exactly, and the closed forms of Levoy et al., "Light Field Microscopy" (2006)."""

import math
from pathlib import Path

import numpy as np
import pytest

from lfproc import LfprocError
from lfproc import geometry as g
from lfproc.camera import Camera

SAMPLES = Path(__file__).resolve().parents[1] / "lfproc" / "samples" / "cameras"
LFM20 = Camera.from_toml(SAMPLES / "lfm-20x.toml")
LFM60 = Camera.from_toml(SAMPLES / "lfm-60x-water.toml")


def _scope_camera(m_obj=20.0, na=0.5, n=1.33, f_tube=180.0, pitch=0.125, f_s=2.433, pixel=0.0065, relay=1.0,
                  wavelength=510.0):
    text = f"""[sensor]
pixel_pitch_mm = {pixel}
[mla]
pitch_mm = {pitch}
focal_length_mm = {f_s}
[microscope]
objective_magnification = {m_obj}
numerical_aperture = {na}
immersion_index = {n}
tube_lens_focal_length_mm = {f_tube}
relay_magnification = {relay}
wavelength_nm = {wavelength}
"""
    return Camera.from_toml_string(text, "scope.toml")


def _trace_to_mla(camera, z_um, angle):
    """Plain paraxial trace of a ray leaving the axial point z (µm, towards the objective) at slope ``angle``.

    Immersion n between sample and objective; objective f_obj = f_tube/M (front focal length n·f_obj in
    the medium), stop at its back focal plane, tube lens f_tube one f_obj + f_tube behind it, MLA at
    the tube lens's back focal plane. Returns (height, slope) at the MLA, lengths in mm.
    """
    scope = camera.main_optics
    n, f_obj, f_tube = scope.immersion_index, scope.objective_focal_length_mm, scope.tube_lens_focal_length_mm
    y, u = 0.0, angle                             # physical slope in the medium
    y += (n * f_obj - z_um * 1e-3) * u            # to the objective (the native plane is n·f_obj in front)
    u = (n * u - y / f_obj) / 1.0                 # refraction into air: n'u' = n u − y·power
    y += (f_obj + f_tube) * u                     # through the stop to the tube lens
    u = u - y / f_tube
    y += f_tube * u                               # to the MLA
    return y, u


@pytest.mark.parametrize("camera", [LFM20, LFM60, _scope_camera(40.0, 0.8, 1.0, 200.0, 0.15, 3.75)])
@pytest.mark.parametrize("z_um", [-30.0, -2.5, 0.0, 7.0, 55.0])
def test_slice_depth_matches_a_plain_ray_trace(camera, z_um):
    # two rays from the point meet w behind the MLA; the views see it at lens j − a·i with a = w/(m̂·f_s)
    (y1, u1), (y2, u2) = _trace_to_mla(camera, z_um, 1e-4), _trace_to_mla(camera, z_um, -2e-4)
    w = -(y1 - y2) / (u1 - u2)                  # y + w·u equal for both rays: the meeting point
    a = w * camera.sample_pitch_mm / (camera.mla_pitch_mm * camera.mla_focal_length_mm)   # paper: w = a·p_m/δ
    geo = g.slice_geometry(camera, a)
    assert geo.z_um == pytest.approx(z_um, rel=1e-9, abs=1e-9)
    assert g.position_parameter(camera, z_um) == pytest.approx(a, rel=1e-9, abs=1e-12)


def test_contract_formula_and_transfer():
    # z_um = a·m̂·f_s·n/M² (f_s in µm), the relay entering only through m̂
    for cam in (LFM20, LFM60):
        scope = cam.main_optics
        expected = cam.m_hat * cam.mla_focal_length_mm * 1e3 * scope.immersion_index / scope.objective_magnification ** 2
        assert g.z_per_a_um(cam) == pytest.approx(expected, rel=1e-12)
        s = g.main_optics_transfer(cam)                 # built lens by lens: afocal and imaging
        assert (s.A, s.D) == pytest.approx((-scope.objective_magnification, -1 / scope.objective_magnification),
                                           rel=1e-12)
        assert abs(s.B) < 1e-12 and abs(s.C) < 1e-12
    assert LFM20.m_hat == 27 and g.z_per_a_um(LFM20) == pytest.approx(27 * 2433 * 1.33 / 400, rel=1e-12)


def test_thin_lens_transfer_is_the_papers_distance():
    # the general conjugate n(B + wD)/(A + wC) reproduces Eq. 21 (evaluated in Newton's form in _slices)
    cam = Camera.from_toml(SAMPLES / "paper-f100.toml")
    for a in (0.5, 1.0, 3.0, 5.0):
        w = a * cam.mla_pitch_mm * cam.mla_focal_length_mm / cam.sample_pitch_mm
        z = -g.main_optics_transfer(cam).object_offset_mm(w)
        assert cam.main_optics.sensor_path_mm(cam.mla_path_mm) + z == pytest.approx(g.slice_distance_mm(cam, a), rel=1e-12)


def test_lateral_sampling_and_levoy_dof():
    # Levoy et al. 2006: one output pixel per lenslet, the lenslet pitch / M in the sample; the microscope's DOF
    # D_tot = λn/NA² + n·e/(M·NA) (Inoué & Spring; verified on MicroscopyU's page, docs/microscope.md), e = pitch
    assert LFM20.main_optics.lateral_sampling_um(LFM20) == pytest.approx(125 / 20)
    assert LFM60.main_optics.lateral_sampling_um(LFM60) == pytest.approx(100 / 60)
    wave = 0.51 * 1.33 / 0.25
    geo = g.slice_geometry(LFM20, 0.0)
    c_na = g.na_views(LFM20)
    geometric = geo.dof_um - wave
    # the paper's border rays over the 2·c_NA + 1 views across the NA: 2·z(1)/(2·c_NA − 1)
    assert geometric == pytest.approx(2 * g.z_per_a_um(LFM20) / (2 * c_na - 1), rel=1e-12)
    # and it tends to Levoy's n·p_m/(M·NA) as views multiply (matched lenslets, NA = M·p_m/(2 f_s))
    ratios = []
    for pixel in (0.0125, 0.0025, 0.0005):
        cam = _scope_camera(20.0, 20 * 0.125 / (2 * 2.5) * 0.999, 1.33, 180.0, 0.125, 2.5, pixel, 1.0, 1e-6)
        levoy = 1.33 * 125 / (20 * cam.main_optics.numerical_aperture)
        ratios.append((g.slice_geometry(cam, 0.0).dof_um) / levoy)
    assert ratios[0] > ratios[1] > ratios[2] > 1.0 and ratios[2] < 1.01


@pytest.mark.parametrize("m_hat", [15, 21, 31])
def test_levoy_dof_of_nu_resolvable_spots(m_hat):
    """Levoy et al.'s DOF of a refocused slice, (2 + N_u)·λ·n/(2·NA²), N_u = W/R_obj the spots resolvable
    behind a lenslet of pitch W, R_obj = 0.47·λ·M/NA (Sparrow): D_tot with e = W and 0.47 taken as ½. A
    design whose samples per lens are those spots (m̂ = N_u) and whose lenslets match the NA: the paper's
    border rays (Eqs. 23–31) plus the wave term agree within 8 % (exactly in the limit but for 0.47 vs ½)."""
    m_obj, n, pitch, f_s = 20.0, 1.33, 0.125, 2.5
    na = m_obj * pitch / (2 * f_s) * 0.999
    wavelength_um = pitch * 1e3 * na / (0.47 * m_obj * m_hat)
    cam = _scope_camera(m_obj, na, n, 180.0, pitch, f_s, pitch / (m_hat + 0.5), 1.0, wavelength_um * 1e3)
    assert cam.m_hat == m_hat
    n_u = pitch * 1e3 * na / (0.47 * wavelength_um * m_obj)
    levoy = (2 + n_u) * wavelength_um * n / (2 * na * na)
    assert g.slice_geometry(cam, 0.0).dof_um == pytest.approx(levoy, rel=0.08)


def test_dof_limits_bracket_the_slice():
    geo = g.slice_geometry(LFM60, np.linspace(-2, 2, 17))
    assert np.all(geo.z_far_um < geo.z_um) and np.all(geo.z_um < geo.z_near_um)
    assert np.allclose(geo.dof_um, geo.z_near_um - geo.z_far_um)
    assert geo.distance_mm is None and geo.records()[0].keys() == {"a", "z_um", "z_near_um", "z_far_um", "dof_um"}


def test_aplanatic_shifts_match_an_exact_sine_condition_trace():
    # an aplanatic objective maps the native-plane point x to −M·x and directions by n·sinθ = M·sinθ'
    cam = LFM60
    scope = cam.main_optics
    m, n = scope.objective_magnification, scope.immersion_index
    sigma_y, sigma_x = g.refocus_slopes(cam, aplanatic=True)
    c, p = cam.center_index, cam.sample_pitch_mm
    inside = g.views_inside_aperture(cam)
    a = 0.4
    z_mm = g.slice_geometry(cam, a).z_um * 1e-3
    for ky in range(cam.m_hat):
        for kx in range(cam.m_hat):
            if not inside[ky, kx]:
                continue
            ux, uy = (kx - c) * p, (ky - c) * p                    # where the view sits under its lens
            d_img = np.array([ux, uy, cam.mla_focal_length_mm])
            d_img /= np.linalg.norm(d_img)
            sx, sy = d_img[0] * m / n, d_img[1] * m / n                # object direction sines (sine condition)
            cz = math.sqrt(1 - sx * sx - sy * sy)
            # the ray from the point at depth z crosses the native plane displaced by −z·(sx, sy)/cz
            # (it travels from z towards the objective, opposite to the image-side direction after inversion)
            x_native = -z_mm * sx / cz, -z_mm * sy / cz
            lens_x = -m * x_native[0] / cam.mla_pitch_mm               # lens index offset at the MLA
            lens_y = -m * x_native[1] / cam.mla_pitch_mm
            # refocusing reads view k at j + a·σ: the point's image in view k sits a·σ from the centre view's
            assert a * sigma_x[ky, kx] == pytest.approx(-lens_x, abs=1e-9)
            assert a * sigma_y[ky, kx] == pytest.approx(-lens_y, abs=1e-9)


def test_paraxial_shifts_are_the_small_angle_limit():
    low = _scope_camera(10.0, 0.05, 1.0, 200.0, 0.2, 20.0, 0.01)
    sy, sx = g.refocus_slopes(low, aplanatic=True)
    c = low.center_index
    k = np.arange(low.m_hat)
    assert np.allclose(sx, (c - k)[None, :], rtol=2e-3) and np.allclose(sy, (c - k)[:, None], rtol=2e-3)
    assert g.refocus_slopes(low, aplanatic=False) is None
    assert g.refocus_slopes(Camera.from_toml(SAMPLES / "paper-f100.toml")) is None


def test_aplanatic_default_follows_paraxial_error_against_dof():
    assert not g.uses_aplanatic(LFM20) and g.uses_aplanatic(LFM60)
    for cam in (LFM20, LFM60):
        error = g.paraxial_depth_error(cam) * g.z_per_a_um(cam)
        assert (error > g.slice_geometry(cam, 1.0).dof_um) == g.uses_aplanatic(cam)
    forced = Camera.from_toml_string(LFM20.to_toml().replace("[decode]", "aplanatic = true\n[decode]"))
    assert g.uses_aplanatic(forced) and g.refocus_slopes(forced) is not None


def test_views_angles_and_na():
    views = g.view_geometry(LFM60)
    scope = LFM60.main_optics
    assert views.baseline_mm is None                                       # orthographic: directions
    inside = views.inside
    sines = np.sin(np.radians(views.angle_deg[inside]))
    assert np.all(np.abs(sines) <= scope.numerical_aperture / scope.immersion_index + 1e-12)
    assert views.angle_deg[LFM60.center_index] == 0.0
    assert np.all(np.sign(views.angle_deg) == -np.sign(views.i))      # the sign of m_i = −i·p_p/f_s
    rec = views.records()[0]
    assert rec.keys() == {"i", "angle_deg", "inside_na"}


def test_z_range_planning_covers_and_steps():
    for cam in (LFM20, LFM60):
        a = g.plan_slices(cam, 25.0, -40.0)                   # from its end nearer the objective to the farther
        geo = g.slice_geometry(cam, a)
        assert geo.z_far_um[0] <= -40.0 and geo.z_near_um[-1] >= 25.0
        assert np.all(geo.z_far_um[1:] <= geo.z_near_um[:-1])                       # no gap
        assert geo.z_far_um[0] == pytest.approx(-40.0, abs=1e-6)                    # the first one starts there
        fewer = g.plan_slices(cam, 25.0, -40.0)[:-1]
        assert g.slice_geometry(cam, fewer).z_near_um[-1] < 25.0                    # one fewer does not reach
    stack = g.plan_slices(LFM20, 10.0, -10.0, step=2.5)
    assert np.allclose(g.slice_geometry(LFM20, stack).z_um, np.arange(-10.0, 10.01, 2.5))
    with pytest.raises(LfprocError, match="step"):
        g.plan_slices(LFM20, 10.0, -10.0, step=0.0)
    with pytest.raises(LfprocError, match="not a valid range"):
        g.plan_slices(LFM20, -10.0, 10.0)                      # NEAR (nearer the objective) first


def test_main_lens_functions_refuse_a_microscope():
    for call in (lambda: g.slice_distance_mm(LFM20, 1.0), lambda: g.refocus_parameter(LFM20, 300.0),
                 lambda: g.infinity_parameter(LFM20)):
        with pytest.raises(LfprocError, match="mm from the sensor|no slice at infinity"):
            call()
    with pytest.raises(LfprocError, match="microscope camera"):
        g.z_per_a_um(Camera.from_toml(SAMPLES / "paper-f100.toml"))


def test_the_relay_enters_only_through_m_hat():
    # the relay images the lenslet focal plane onto the sensor: a 1.4286x relay in front of 6.5 µm pixels
    # samples like 4.55 µm pixels at the lenslet focus without one
    relay = _scope_camera(pixel=0.0065, relay=1.4286)
    direct = _scope_camera(pixel=0.0065 / 1.4286, relay=1.0)
    assert relay.m_hat == direct.m_hat == 27
    assert relay.pitch_px == pytest.approx(direct.pitch_px, rel=1e-12)
    a = np.array([-0.3, 0.05, 0.2])
    assert np.allclose(g.slice_geometry(relay, a).z_um, g.slice_geometry(direct, a).z_um, rtol=1e-12)
    # a stronger relay gives more samples per lens; each view step is then a finer angle, so one unit of
    # a (one lens of shift per view step) is a proportionally larger depth: z(1) ∝ m̂
    strong = _scope_camera(pixel=0.0065, relay=2.6)
    assert strong.m_hat == 49
    assert g.z_per_a_um(strong) / g.z_per_a_um(relay) == pytest.approx(49 / 27, rel=1e-12)
    # while the depth of a view's one-sample parallax (z(1)/m̂ per lens shift of one sample) stays the same
    assert g.z_per_a_um(strong) / strong.m_hat == pytest.approx(g.z_per_a_um(relay) / relay.m_hat, rel=1e-12)


def test_aplanatic_shifts_around_an_off_centre_disc_match_the_trace():
    """Views read around a disc centre off the lens centre (c_y, c_x samples) stand for the rays at
    u = (k − c + centre)·p_p; their shifts relative to the central view are those of an exact sine-condition
    trace of those rays."""
    cam = LFM60
    m, n = cam.main_optics.objective_magnification, cam.main_optics.immersion_index
    centre = (-0.6, 0.9)
    sigma_y, sigma_x = g.refocus_slopes(cam, aplanatic=True, centre=centre)
    c, p = cam.center_index, cam.sample_pitch_mm
    z_mm = g.slice_geometry(cam, 0.3).z_um * 1e-3

    def lens_offset(ky, kx):
        d = np.array([(kx - c + centre[1]) * p, (ky - c + centre[0]) * p, cam.mla_focal_length_mm])
        d /= np.linalg.norm(d)
        sx, sy = d[0] * m / n, d[1] * m / n
        cz = math.sqrt(1 - sx * sx - sy * sy)
        return m * z_mm * sy / cz / cam.mla_pitch_mm, m * z_mm * sx / cz / cam.mla_pitch_mm

    y0, x0 = lens_offset(c, c)
    inside = g.views_inside_aperture(cam)
    for ky, kx in zip(*np.nonzero(inside)):
        ly, lx = lens_offset(ky, kx)
        assert 0.3 * sigma_x[ky, kx] == pytest.approx(-(lx - x0), abs=1e-9)
        assert 0.3 * sigma_y[ky, kx] == pytest.approx(-(ly - y0), abs=1e-9)
