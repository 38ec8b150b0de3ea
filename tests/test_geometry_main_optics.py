"""One ray model for every main optics (issue 31): the geometry asks the optics' interface, never their kind.

* a microscope's slices through the generic ray model are the closed form z = a·m̂·f_s·n/M² and the DOF of
  the microscope formula it had before (the paper's border rays over the c_NA views inside the NA, plus the
  wave term λ·n/NA²), computed here in plain numpy;
* every MainOptics implementation keeps the interface: its object position is its own transfer's conjugate;
* the geometry functions that used to branch on the kind give the same answers through the interface.

That nothing outside the optics asks the kind is checked for the whole package in tests/test_architecture.py.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from focus import focused
from lfproc import LfprocError
from lfproc import geometry as g
from lfproc.camera import NATIVE_PLANE_UM, SENSOR_MM, Camera, MainLens, MainOptics, Microscope
from scopefile import microscope_toml

ROOT = Path(__file__).resolve().parents[1]
CAMERAS = ROOT / "lfproc" / "samples" / "cameras"


def _camera(name):
    return Camera.from_toml(CAMERAS / f"{name}.toml")


def _scope_camera(m_obj, na, n, f_tube, pitch, f_s, pixel, relay=1.0, wavelength=510.0):
    text = microscope_toml(name=None, pixel=pixel, pitch=pitch, f_s=f_s, grid=None, magnification=m_obj, na=na, n=n,
                           f_tube=f_tube, relay=relay, wavelength=wavelength)
    return Camera.from_toml_string(text, "scope.toml")


SCOPES = {"lfm-20x": _camera("lfm-20x"), "lfm-60x-water": _camera("lfm-60x-water"),
          "40x-relay": _scope_camera(40.0, 0.8, 1.0, 200.0, 0.15, 3.75, 0.0065, relay=0.8, wavelength=600.0),
          "10x-air-narrow": _scope_camera(10.0, 0.1, 1.0, 165.0, 0.1, 2.0, 0.0074)}


# ------------------------------------------------------------------ (a) a microscope: the closed forms
def _c_na(camera, m_obj, na):
    """Largest view offset i <= c whose image-side ray sine i·p/|(i·p, f_s)| is within NA/M (plain loop)."""
    best = 0
    for i in range(camera.center_index + 1):
        u = i * camera.mla_pitch_mm / camera.m_hat
        if u / math.sqrt(u * u + camera.mla_focal_length_mm ** 2) <= na / m_obj * (1 + 1e-12):
            best = i
    return best


def _microscope_closed_form(camera, a, extent=None):
    """(z, z_near, z_far, dof) in µm: z = a·m̂·f_s·n/M², the paper's bounding border-ray pairs over c views
    (c = c_NA, at least 1, unless the views summed are named), the wave term λ·n/NA² split evenly."""
    scope = camera.main_optics
    m_obj, na, n = scope.objective_magnification, scope.numerical_aperture, scope.immersion_index
    wavelength_um = (550.0 if scope.wavelength_nm is None else scope.wavelength_nm) * 1e-3
    zeta = camera.m_hat * camera.mla_focal_length_mm * 1e3 * n / m_obj ** 2
    c = min(max(_c_na(camera, m_obj, na), 1), camera.center_index) if extent is None else extent
    limits = []
    for s in (1.0, -1.0):
        big_a = np.where(2 * a * c + s >= 0, (2 * a * c + s) / (2 * c - s), (2 * a * c + s) / (2 * c + s))
        limits.append(zeta * big_a)
    z = zeta * a
    wave = wavelength_um * n / na ** 2
    upper = np.maximum(np.maximum(*limits), z) + wave / 2
    lower = np.minimum(np.minimum(*limits), z) - wave / 2
    return z, upper, lower, upper - lower


@pytest.mark.parametrize("name", sorted(SCOPES))
@pytest.mark.parametrize("extent", [None, 1.0, 2.5])
def test_microscope_slices_are_the_closed_form_and_the_previous_dof(name, extent):
    camera = SCOPES[name]
    a = np.concatenate([np.linspace(-4.0, 4.0, 33), [0.013, -0.27, 1.0 / (2 * camera.center_index)]])
    geo = g.slice_geometry(camera, a, extent)
    z, near, far, dof = _microscope_closed_form(camera, a, extent)
    assert geo.space == NATIVE_PLANE_UM and geo.distance_mm is None
    np.testing.assert_allclose(geo.depth, z, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(geo.z_near_um, near, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(geo.z_far_um, far, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(geo.dof_um, dof, rtol=1e-12, atol=1e-12)
    # microscope_slices is slice_geometry, and a scalar a gives floats
    one = g.microscope_slices(camera, 0.75, extent)
    assert isinstance(one.z_um, float) and one.z_um == pytest.approx(float(_microscope_closed_form(camera, 0.75,
                                                                                                   extent)[0]))


def test_the_microscope_dof_has_the_wave_term_and_the_na_views():
    # an objective filling only some views: the DOF of slice 0 is the border rays' 2·z(1)/(2·c_NA − 1) + λn/NA²
    camera = SCOPES["10x-air-narrow"]
    scope = camera.main_optics
    wave = scope.wavelength_mm * 1e3 * scope.immersion_index / scope.numerical_aperture ** 2
    c_na = _c_na(camera, scope.objective_magnification, scope.numerical_aperture)
    assert g.na_views(camera) == c_na and 1 <= c_na < camera.center_index
    geo = g.slice_geometry(camera, 0.0)
    assert geo.dof - wave == pytest.approx(2 * g.z_per_a_um(camera) / (2 * c_na - 1), rel=1e-12)


# ------------------------------------------------------------------ (c) every MainOptics keeps the interface
def _lens_with_prescription():
    return _camera("double-gauss-f100")


OPTICS = {
    "main lens": _camera("paper-f100").main_optics,
    "main lens, b_U > f_U": _camera("paper-f200-b10").main_optics,
    "main lens, finite exit pupil": _camera("illum-like").main_optics,
    "main lens without f-number": MainLens(50.0, 52.5, principal_plane_gap_mm=-3.0),
    "main lens with a prescription": _lens_with_prescription().main_optics,
    "main lens with a prescription, focused near": focused(_lens_with_prescription(), 900.0).main_optics,
    "microscope 20x": SCOPES["lfm-20x"].main_optics,
    "microscope 60x water": SCOPES["lfm-60x-water"].main_optics,
    "microscope with relay": SCOPES["40x-relay"].main_optics,
}


def _transfer_position(optics, w_mm, mla_path_mm):
    """s = n·(B + w·D)/(A + w·C) from the transfer's reference plane (towards the optics), in the optics'
    object space: mm from the sensor (the sensor is mla_path + b_U + H1U–H2U behind H1U, the object s in
    front of it is at −s), or µm from the native object plane, positive towards the objective (+s)."""
    t = optics.transfer()
    s = t.index * (t.B + w_mm * t.D) / (t.A + w_mm * t.C)
    if isinstance(optics, MainLens):
        return mla_path_mm + optics.image_distance_mm + optics.principal_plane_gap_mm - s
    return s * optics.object_space.per_mm


@pytest.mark.parametrize("name", sorted(OPTICS))
def test_every_main_optics_implements_the_interface(name):
    optics = OPTICS[name]
    assert isinstance(optics, MainOptics)
    assert isinstance(optics, (MainLens, Microscope))
    space = optics.object_space
    assert space in (SENSOR_MM, NATIVE_PLANE_UM)
    assert space.position_key == space.keys[0] and len(space.keys) == 4
    assert space.per_mm == (1000.0 if isinstance(optics, Microscope) else 1.0)
    # the aperture as a sine at the MLA: 1/(2N) of a lens (None without N), NA/M of an objective
    camera = SCOPES["lfm-20x"] if isinstance(optics, Microscope) else _camera("paper-f100")
    if isinstance(optics, Microscope):
        assert optics.image_aperture_sine == optics.numerical_aperture / optics.objective_magnification
        assert optics.place_views(camera, [1.0]).orthographic and math.isinf(optics.exit_pupil_distance_mm)
        assert optics.wave_depth_of_field() > 0
    else:
        expected = None if optics.f_number is None else 1.0 / (2.0 * optics.f_number)
        assert optics.image_aperture_sine == expected
        assert not optics.place_views(camera, [1.0]).orthographic and optics.relay_magnification == 1.0
        assert optics.wave_depth_of_field() == 0.0
    assert optics.relay_magnification > 0
    assert isinstance(optics.describe(), str) and optics.describe()
    extent = optics.lit_view_extent(0.01, 2.5, 6)
    assert 0.0 <= extent <= 6.0


@pytest.mark.parametrize("name", sorted(OPTICS))
def test_object_position_is_the_transfers_conjugate(name):
    optics = OPTICS[name]
    mla_path = 2.437
    slope_gap = 0.0123
    if isinstance(optics, MainLens):          # real conjugates in front of the lens: w > −(b_U − f_U)
        eps = optics.image_distance_mm - optics.focal_length_mm
        w_values = [0.02, 0.3, 1.7, 12.0, 150.0] + ([-0.5 * eps] if eps > 0 else [])
    else:                                     # every depth, either side of the native object plane
        w_values = [-40.0, -3.0, -0.2, 0.0, 0.05, 2.5, 31.0]
    for w in w_values:
        got = optics.object_position(w * slope_gap, 1.0, slope_gap, mla_path)
        assert float(got) == pytest.approx(_transfer_position(optics, w, mla_path), rel=1e-9, abs=1e-9), w
    # vectorised alike
    w = np.array(w_values)
    np.testing.assert_allclose(optics.object_position(w * slope_gap, 1.0, slope_gap, mla_path),
                               [_transfer_position(optics, v, mla_path) for v in w], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("name", ["paper-f100", "illum-like", "double-gauss-f100", "lfm-20x", "lfm-60x-water"])
def test_slice_geometry_asks_the_optics_where_the_rays_meet(name):
    # the central pair (A = C = a) meets A·p_m/N behind the MLA; its object point is the optics' own answer
    camera = _camera(name)
    optics = camera.main_optics
    a = np.array([0.25, 0.5, 1.0, 2.0, 3.5])
    slope_gap = camera.sample_pitch_mm / camera.mla_focal_length_mm - a * camera.mla_pitch_mm * g.pupil_curvature(
        camera)
    expected = optics.object_position(a, camera.mla_pitch_mm, slope_gap, camera.mla_path_mm)
    geo = g.slice_geometry(camera, a)
    np.testing.assert_array_equal(geo.depth, expected)
    assert geo.space == camera.main_optics.object_space
    assert list(geo.records()[0]) == ["a", *camera.main_optics.object_space.keys]


# ------------------------------------------------------------------ the converted geometry functions
def test_usable_range_follows_the_object_space():
    scope, lens = SCOPES["lfm-20x"], _camera("paper-f100-b10")
    assert g.usable_a_range(scope) == (-math.inf, math.inf)
    low, high = g.usable_a_range(lens)
    assert low == float(g.infinity_parameter(lens)) and high == math.inf
    z1 = float(g.slice_geometry(scope, 1.0).depth)
    assert g.usable_range_text(scope, -1.0, 1.0) == f"a from -1 (z = {-z1:+.2f} µm) to +1 (z = {z1:+.2f} µm)"
    front = g.front_focal_plane_mm(lens)
    assert g.usable_range_text(lens) == f"a from {g.format_a(low, +1)} (infinity) to +inf (approaching the main lens's front focal plane at {front:.1f} mm)"
    # in positions (the argument a user gave), low to high, each end with its a
    assert g.usable_range_text(scope, -1.0, 1.0, "z_um") == f"z_um from {-z1:+.2f} µm to {z1:+.2f} µm (a from -1 to +1)"
    assert g.usable_range_text(lens, None, 2.0, "distance_mm").endswith(f" mm to infinity (a from +2 to "
                                                                        f"{g.format_a(low, +1)})")


def test_views_inside_the_aperture_follow_the_optics():
    scope = SCOPES["lfm-60x-water"]
    np.testing.assert_array_equal(g.views_inside_aperture(scope), scope.main_optics.inside_aperture(scope))
    # orthographic views: the sine of each view's image-side ray within NA/M (plain loop)
    c, p, f_s = scope.center_index, scope.sample_pitch_mm, scope.mla_focal_length_mm
    sine = scope.main_optics.image_aperture_sine
    expected = np.array([[math.hypot((ky - c) * p, (kx - c) * p) / math.sqrt(((ky - c) * p) ** 2 + ((kx - c) * p) ** 2
                                                                          + f_s ** 2) <= sine * (1 + 1e-12)
                          for kx in range(scope.m_hat)] for ky in range(scope.m_hat)])
    np.testing.assert_array_equal(g.views_inside_aperture(scope), expected)
    lens = _camera("paper-f100")
    radius = lens.main_optics.focal_length_mm / (2 * lens.main_optics.f_number)
    pos = g.view_positions_mm(lens)
    np.testing.assert_array_equal(g.views_inside_aperture(lens),
                                  pos[:, None] ** 2 + pos[None, :] ** 2 <= radius ** 2 * (1 + 1e-12))


def test_apertures_of_orthographic_views_are_sines():
    scope = SCOPES["lfm-20x"].main_optics
    camera = SCOPES["lfm-20x"]
    widest, _ = g.aperture_limits(camera)
    assert widest == pytest.approx(scope.objective_magnification / (2 * scope.numerical_aperture), rel=1e-15)
    assert g.equivalent_numerical_aperture(camera, 2.0) == pytest.approx(
        scope.objective_magnification / (2 * g.equivalent_f_number(camera, 2.0)), rel=1e-15)
    assert g.equivalent_numerical_aperture(camera) == scope.numerical_aperture   # capped at the objective's
    assert g.aperture_text(camera, 2.0).startswith("NA ")
    assert g.aperture_text(_camera("paper-f100"), 2.0).startswith("f/")
    with pytest.raises(LfprocError, match="equivalent numerical aperture needs object-side telecentric optics"):
        g.equivalent_numerical_aperture(_camera("paper-f100"))


def test_virtual_cameras_and_triangulation_refuse_orthographic_views():
    camera = SCOPES["lfm-20x"]
    for call in (lambda: g.view_positions_mm(camera), lambda: g.baseline_mm(camera), lambda: g.view_tilts_deg(camera)):
        with pytest.raises(LfprocError, match="orthographic"):
            call()
    with pytest.raises(LfprocError, match="needs a main lens"):
        g.triangulate(camera, [0.5], 1)


def test_integer_gaps_and_uncovered_depths_in_either_object_space():
    # every view summed (the NA's for a microscope): integer slices leave gaps (Section 5.2), in µm as in mm
    for camera in (SCOPES["lfm-60x-water"], _camera("paper-f100")):
        a = np.arange(0.0, 6.0)
        geo = g.slice_geometry(camera, a)
        gaps = g.integer_slice_gaps(camera, a)
        assert gaps, camera.name
        for k, near_end, far_end in gaps:
            i = int(k)
            assert near_end == geo.far[i + 1] and far_end == geo.near[i]      # the limits either side of the gap
            # the gap lies between the two slices' intervals, and no slice covers its middle
            middle = 0.5 * (near_end + far_end)
            lo, hi = np.minimum(geo.near, geo.far), np.maximum(geo.near, geo.far)
            assert not np.any((lo <= middle) & (middle <= hi))
        low = min(min(gap[1:]) for gap in gaps) - 1.0
        high = max(max(gap[1:]) for gap in gaps) + 1.0
        uncovered = g.uncovered_depths(camera, a, low, high)
        assert all(lo < hi for lo, hi in uncovered)
        # every interior gap of the integer slices is an uncovered interval
        for _, near_end, far_end in gaps:
            assert (min(near_end, far_end), max(near_end, far_end)) in uncovered


def test_calibration_blames_the_relay_of_an_afocal_objective_not_an_exit_pupil():
    from lfproc.calibrate import exit_pupil_warning, implied_exit_pupil
    scope, lens = SCOPES["lfm-20x"], _camera("paper-f100")
    estimate = implied_exit_pupil(scope.pitch_px * 1.01, 1e-4, scope)
    assert math.isinf(estimate.distance_mm) and estimate.range_mm == (math.inf, math.inf)
    assert "microscope.relay_magnification" in exit_pupil_warning("W.tif", estimate, scope)
    lens_estimate = implied_exit_pupil(lens.pitch_px * 1.01, 1e-4, lens)
    assert math.isfinite(lens_estimate.distance_mm)
    assert "main_lens.exit_pupil_distance_mm" in exit_pupil_warning("W.tif", lens_estimate, lens)


def test_the_lens_renderer_refuses_a_microscope_and_the_microscope_renderer_a_lens():
    from lfproc.simulate import render_microscope_views
    from lfproc.simulate._checks import _require_f_number
    with pytest.raises(LfprocError, match="traces a main lens"):
        _require_f_number(SCOPES["lfm-20x"])
    with pytest.raises(LfprocError, match="needs a microscope camera"):
        render_microscope_views(_camera("paper-f100"), None, (2, 2))   # refused before the scene is read
