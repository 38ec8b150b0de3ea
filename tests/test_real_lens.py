"""Real lenses: prescriptions, their cardinal points, and the model's rays traced exactly (issue 33).

References: the thick-lens closed forms (Hecht, Optics, §6.1), optiland's own paraxial analysis and
its exact ray tracer (an independent library tracing the same rays through the reversed lens), and
the paraxial model itself (the rays must be the ones it intersects).
"""

import json
import math
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import SAMPLES, assert_clean_error, run_cli

from focus import focused
from lfproc import LfprocError
from lfproc import geometry as g
from lfproc.camera import Camera, LensPrescription, Surface, read_zmx

CAMS = SAMPLES / "cameras"
DG = CAMS / "double-gauss-f100.toml"                       # the lens with its own stop, inline surfaces
TELE = CAMS / "double-gauss-f100-telecentric.toml"         # its stop moved to the front focal plane
DG_ZMX = CAMS / "double-gauss-f100-zmx.toml"               # the same lens from the .zmx (needs lfproc[lens])
ZMX = SAMPLES / "lenses" / "double-gauss-f100.zmx"


def _camera_text(main_lens: str) -> str:
    return ("[sensor]\npixel_pitch_mm = 0.01\n[mla]\npitch_mm = 0.25\nfocal_length_mm = 2.749\n"
            "principal_plane_gap_mm = 0.374\n[main_lens]\n" + main_lens + "\n[decode]\nmicro_image_px = 25\n")


def _surfaces_text(camera: Camera) -> str:
    return camera.to_toml().split("[main_lens]\n")[1].split("[decode]")[0]


def _cameras():
    """The sample lens at b_U = f_U and f_U + 10/20 mm, with its own stop and telecentric."""
    out = []
    for path in (DG, TELE):
        cam = Camera.from_toml(path)
        for extra in (0.0, 10.0, 20.0):
            out.append(cam.with_optics(cam.main_optics.with_prescription(cam.main_optics.prescription, cam.main_optics.focal_length_mm + extra)))
    return out


# ----------------------------------------------------------------- prescriptions and cardinal points
def test_thick_lens_cardinal_points_match_the_closed_forms():
    n, r1, r2, t = 1.5, 50.0, -80.0, 8.0
    lens = LensPrescription((Surface(r1, t, n, stop=True), Surface(r2, 30.0, 1.0)))
    f = 1.0 / ((n - 1) * (1 / r1 - 1 / r2 + (n - 1) * t / (n * r1 * r2)))      # lensmaker's equation
    assert lens.focal_length_mm == pytest.approx(f, rel=1e-12)
    assert lens.front_principal_plane_mm == pytest.approx(-f * (n - 1) * t / (n * r2), rel=1e-12)
    assert lens.rear_principal_plane_mm == pytest.approx(t - f * (n - 1) * t / (n * r1), rel=1e-12)
    # the stop on the first vertex, imaged by the second surface: n'/s' − n/s = (n' − n)/R
    s_img = 1.0 / ((1.0 - n) / r2 + n / -t)
    assert lens.exit_pupil_mm == pytest.approx(t + s_img, rel=1e-12)
    # with the stop in the front focal plane the exit pupil is at infinity (the paper's telecentric case)
    assert math.isinf(lens.with_stop_at_front_focal_plane().exit_pupil_mm)


def test_cardinal_points_agree_with_optilands_paraxial_analysis_and_table_1():
    import optiland  # noqa: F401  (the test extra installs it: the independent reference must not be skipped)
    from optiland.samples.objectives import DoubleGauss
    ref = DoubleGauss()
    lens = read_zmx(ZMX, 587.6)
    p = ref.paraxial
    image_z = lens.length_mm + 61.487536               # the sample's image plane, where optiland measures P2, XPL
    assert lens.focal_length_mm == pytest.approx(float(p.f2()), rel=1e-9)
    assert lens.front_principal_plane_mm == pytest.approx(float(p.P1()), rel=1e-9)
    assert lens.rear_principal_plane_mm == pytest.approx(image_z + float(p.P2()), rel=1e-9)
    assert lens.exit_pupil_mm == pytest.approx(image_z + float(p.XPL()), rel=1e-9)
    # the same design as the paper's f100 (Table 1: 99.515 mm, H1U-H2U = -33.184 mm), other glass data
    assert lens.focal_length_mm == pytest.approx(99.515, rel=5e-3)
    assert lens.principal_plane_gap_mm == pytest.approx(-33.184, rel=0.1)
    # and the inline sample camera is that lens
    inline = Camera.from_toml(DG).main_optics.prescription
    assert inline.focal_length_mm == pytest.approx(lens.focal_length_mm, rel=1e-12)
    assert Camera.from_toml(DG_ZMX).main_optics.exit_pupil_distance_mm == pytest.approx(
        Camera.from_toml(DG).main_optics.exit_pupil_distance_mm, rel=1e-12)


@pytest.mark.parametrize("camera", _cameras(), ids=lambda c: f"{c.name}-bU{c.main_optics.image_distance_mm:.1f}")
def test_a_prescription_camera_equals_the_camera_typed_by_hand(camera):
    hand = Camera.from_toml_string(_camera_text(
        f"focal_length_mm = {camera.main_optics.focal_length_mm!r}\n"
        f"principal_plane_gap_mm = {camera.main_optics.principal_plane_gap_mm!r}\n"
        f"image_distance_mm = {camera.main_optics.image_distance_mm!r}\n"
        + ("" if camera.telecentric else f"exit_pupil_distance_mm = {camera.main_optics.exit_pupil_distance_mm!r}\n")))
    lens_only = Camera.from_toml_string(_camera_text("\n".join(     # the surfaces and b_U only
        line for line in _surfaces_text(camera).splitlines()
        if not line.startswith(("focal_length_mm", "principal_plane_gap_mm", "exit_pupil_distance_mm", "f_number")))))
    assert lens_only.main_optics.prescription is not None and hand.main_optics.prescription is None
    a = np.arange(-1.0, 6.01, 0.25)
    for one, two in ((g.slice_geometry(lens_only, a), g.slice_geometry(hand, a)),
                     (g.view_geometry(lens_only), g.view_geometry(hand))):
        for key, value in vars(one).items():
            if value is None or key == "space":
                assert vars(two)[key] == value
                continue
            np.testing.assert_allclose(value, vars(two)[key], rtol=1e-9, atol=1e-12)
    s, t = g.main_optics_transfer(lens_only), g.main_optics_transfer(hand)   # surfaces vs thick lens
    np.testing.assert_allclose([s.A, s.B, s.C, s.D], [t.A, t.B, t.C, t.D], rtol=1e-9, atol=1e-12)


def test_hand_written_values_must_agree_with_the_prescription():
    surfaces = _surfaces_text(Camera.from_toml(DG)).split("wavelength_nm")[1]
    body = "focus_distance_mm = inf\nwavelength_nm" + surfaces
    f_u = Camera.from_toml(DG).main_optics.focal_length_mm
    ok = Camera.from_toml_string(_camera_text(f"focal_length_mm = {f_u * 1.0005!r}\n" + body))
    assert ok.main_optics.focal_length_mm == f_u                      # the lens's own value is used
    for key, value, named in (("focal_length_mm", f_u * 1.003, "paraxial focal length"),
                              ("principal_plane_gap_mm", -33.184, "principal plane gap"),
                              ("exit_pupil_distance_mm", "inf", "exit pupil")):
        text = f"{key} = {value!r}\n" if not isinstance(value, str) else f"{key} = {value}\n"
        with pytest.raises(LfprocError) as err:
            Camera.from_toml_string(_camera_text(text + body), source="cam.toml")
        message = str(err.value)
        assert "cam.toml" in message and named in message and "\n" not in message
        assert (str(value) if isinstance(value, str) else str(value)[:6]) in message


def test_prescription_camera_round_trips_and_refocuses_with_its_own_exit_pupil():
    cam = Camera.from_toml(DG)
    assert Camera.from_toml_string(cam.to_toml()) == cam
    near = focused(cam, 600.0)
    assert near.main_optics.exit_pupil_distance_mm == pytest.approx(
        cam.main_optics.exit_pupil_distance_mm + near.main_optics.image_distance_mm - cam.main_optics.image_distance_mm, rel=1e-12)


def test_missing_lens_extra_is_one_line(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "optiland", None)
    monkeypatch.setitem(sys.modules, "optiland.materials", None)
    with pytest.raises(LfprocError) as err:
        read_zmx(ZMX, 587.6)
    assert "pip install 'lfproc[lens]'" in str(err.value) and "\n" not in str(err.value)
    code = ("import sys; sys.modules['optiland'] = None; sys.modules['optiland.materials'] = None\n"
            f"from lfproc.cli import main; sys.exit(main(['geometry', '--camera', {str(DG_ZMX)!r}]))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert_clean_error(proc, "pip install 'lfproc[lens]'", "double-gauss-f100.zmx")


# ----------------------------------------------------------------- the rays are the model's
@pytest.mark.parametrize("camera", _cameras()[::2], ids=lambda c: f"{c.name}-bU{c.main_optics.image_distance_mm:.1f}")
def test_the_traced_rays_meet_where_the_paraxial_model_says(camera):
    """Traced paraxially (the prescription's own matrices), the rays give slice_geometry and the views."""
    from lfproc.geometry._real_rays import slice_rays, view_rays
    s = g.main_optics_transfer(camera)
    a = np.array([0.5, 1.0, 2.0, 3.0, 5.0])
    y0, mu = slice_rays(camera, a)
    y_h, u_h = s.D * y0 - s.B * mu, -s.C * y0 + s.A * mu      # back to H1U: the inverse of S (det 1)
    d = camera.main_optics.sensor_path_mm(camera.mla_path_mm) + y_h / u_h
    geo = g.slice_geometry(camera, a)
    np.testing.assert_allclose(d[:3], [geo.distance_mm, geo.near_mm, geo.far_mm], rtol=1e-9)
    i = np.arange(-12, 13)
    y0, mu = view_rays(camera, i)
    y_h, u_h = s.D * y0 - s.B * mu, -s.C * y0 + s.A * mu
    z = (y_h[:, -1] - y_h[:, 0]) / (u_h[:, 0] - u_h[:, -1])
    np.testing.assert_allclose(y_h[:, 0] + u_h[:, 0] * z, g.view_positions_mm(camera, i), atol=1e-9)
    np.testing.assert_allclose(np.degrees(np.arctan(u_h[:, 12])), g.view_tilts_deg(camera, i), atol=1e-9)


# ----------------------------------------------------------------- real rays against optiland
def _reversed_optiland(camera):
    """The main lens in optiland, reversed: light from the MLA towards the object."""
    from optiland import optic
    from optiland.materials import IdealMaterial
    lens = camera.main_optics.prescription
    surf, before = list(lens.surfaces), lens.indices_before()
    z_mla = lens.rear_principal_plane_mm + camera.main_optics.image_distance_mm
    rev = optic.Optic()
    rev.surfaces.add(index=0, radius=np.inf, thickness=z_mla - lens.length_mm)
    for j, k in enumerate(range(len(surf) - 1, -1, -1), 1):
        material = "air" if before[k] == 1.0 else IdealMaterial(n=before[k])
        rev.surfaces.add(index=j, radius=-surf[k].radius_mm, thickness=surf[k - 1].thickness_mm if k else 50.0,
                         material=material, is_stop=j == 1)
    rev.surfaces.add(index=len(surf) + 1)
    rev.set_aperture(aperture_type="EPD", value=10.0)
    rev.fields.add(y=0)
    rev.wavelengths.add(value=lens.wavelength_nm / 1000.0, is_primary=True)
    return rev, z_mla


def _optiland_object_rays(camera, y0, mu):
    """(z, y, dz, dy) of rays from the MLA after the lens, in lfproc's lens coordinates, traced by optiland."""
    from optiland.rays import RealRays
    rev, z_mla = _reversed_optiland(camera)
    y0, mu = np.ravel(y0), np.ravel(mu)
    norm = np.sqrt(1.0 + mu * mu)
    z0 = float(np.ravel(rev.surfaces.positions)[0])
    rays = RealRays(0 * y0, y0, np.full_like(y0, z0), 0 * y0, -mu / norm, 1.0 / norm, 1.0 + 0 * y0,
                    np.full_like(y0, camera.main_optics.prescription.wavelength_nm / 1000.0))
    rev.surfaces.trace(rays)
    z, y, m, n = (np.asarray(v, dtype=np.float64) for v in (rays.z, rays.y, rays.M, rays.N))
    lens = camera.main_optics.prescription
    return lens.length_mm - z, y, -n, m        # mirror z back: reversed z' = last vertex − z


@pytest.mark.parametrize("camera", _cameras(), ids=lambda c: f"{c.name}-bU{c.main_optics.image_distance_mm:.1f}")
def test_real_ray_distances_match_optilands_exact_trace(camera):
    import optiland  # noqa: F401  (the test extra installs it: the independent reference must not be skipped)
    from lfproc.geometry._real_rays import slice_rays
    a = np.array([0.25, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0])
    y0, mu = slice_rays(camera, a)
    z, y, dz, dy = _optiland_object_rays(camera, y0, mu)
    z_sensor = (camera.main_optics.prescription.rear_principal_plane_mm + camera.main_optics.image_distance_mm
                + camera.mla_focal_length_mm + camera.mla_principal_plane_gap_mm)
    ref = (z_sensor - (z - y / dy * dz)).reshape(y0.shape)
    real = g.real_ray_slices(camera, a)
    mine = np.array([real.distance_mm, real.near_mm, real.far_mm])
    checked = np.isfinite(mine)
    assert checked.sum() >= 9
    np.testing.assert_allclose(mine[checked], ref[:3][checked], rtol=1e-6)
    spread = ref[3:].max(0) - ref[3:].min(0)
    np.testing.assert_allclose(real.spread_mm[checked[0]], spread[checked[0]], rtol=1e-6, atol=1e-9)
    # views: the least-squares point and the mean angle of optiland's rays
    from lfproc.geometry._real_rays import view_rays
    i = np.array([-12.0, -5.0, 1.0, 12.0])
    y0, mu = view_rays(camera, i)
    z, y, dz, dy = (v.reshape(y0.shape) for v in _optiland_object_rays(camera, y0, mu))
    views = g.real_ray_views(camera, i)
    for k in range(len(i)):             # rows: −dy·Z + dz·Y = −dy·z + dz·y for each ray's line
        lhs = np.c_[-dy[k], dz[k]]
        (zc, yc), *_ = np.linalg.lstsq(lhs, -dy[k] * z[k] + dz[k] * y[k], rcond=None)
        assert views.position_mm[k] == pytest.approx(yc, rel=1e-6)
        assert views.distance_mm[k] == pytest.approx(z_sensor - zc, rel=1e-6)
        assert views.tilt_deg[k] == pytest.approx(np.degrees(np.arctan2(-dy[k], -dz[k])).mean(), rel=1e-6, abs=1e-12)


def test_the_telecentric_experiment_shows_the_papers_pattern_and_nulls_inside_the_lens():
    tele = g.real_ray_slices(Camera.from_toml(TELE), [1, 2, 3, 4, 5])
    para = g.slice_geometry(Camera.from_toml(TELE), np.array([1, 2, 3, 4, 5.0]))
    for p, r in ((para.near_mm, tele.near_mm), (para.distance_mm, tele.distance_mm), (para.far_mm, tele.far_mm)):
        err = (p - r) / p * 100
        assert np.all((err > 0.01) & (err < 1.0)), err          # tenths of a percent, as Table 2
    own = Camera.from_toml(DG)
    records = g.real_ray_slices(own, [-0.5, 1, 4]).records()
    assert records[0]["distance_mm"] is None                     # beyond infinity: no crossing in front
    assert records[1]["distance_mm"] == pytest.approx(g.slice_distance_mm(own, 1.0), rel=2e-3)
    first_vertex = own.main_optics.sensor_path_mm(own.mla_path_mm) + own.main_optics.prescription.front_principal_plane_mm
    assert g.slice_distance_mm(own, 4.0) < first_vertex                          # paraxially inside the lens
    assert records[2] == dict(distance_mm=None, near_mm=None, far_mm=None, spread_mm=None)


@pytest.mark.alone
def test_a_101_slice_sweep_is_fast():
    cam = Camera.from_toml(TELE)
    a = np.linspace(0, 10, 101)
    g.real_ray_slices(cam, a)
    start = time.perf_counter()
    g.real_ray_slices(cam, a)
    g.real_ray_views(cam)
    assert time.perf_counter() - start < 0.5


# ----------------------------------------------------------------- command line and sidecars
def test_geometry_real_rays_json_follows_the_contract_and_stays_light():
    proc = run_cli("geometry", "--camera", DG, "--a", "-0.5,0:2", "--real-rays", "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert [sorted(s["real_rays"]) for s in data["slices"]] == [["distance_mm", "far_mm", "near_mm", "spread_mm"]] * 4
    assert data["slices"][0]["real_rays"]["distance_mm"] is None
    assert {"position_mm", "tilt_deg"} <= set(data["views"][0]["real_rays"])
    real = g.real_ray_slices(Camera.from_toml(DG), [1.0]).records()[0]
    assert data["slices"][2]["real_rays"] == real
    table = run_cli("geometry", "--camera", TELE, "--a", "1", "--real-rays").stdout
    err = (g.slice_distance_mm(Camera.from_toml(TELE), 1.0) - real_d(TELE)) / g.slice_distance_mm(
        Camera.from_toml(TELE), 1.0) * 100
    assert f"{err:.3f}" in table and "real rays through 12 surfaces" in table
    assert_clean_error(run_cli("geometry", "--camera", CAMS / "paper-f100.toml", "--real-rays"), "--real-rays",
                       "[[main_lens.surfaces]]")
    code = (f"import sys, io, contextlib; from lfproc.cli import main\n"
            f"with contextlib.redirect_stdout(io.StringIO()): main(['geometry', '--camera', {str(DG)!r}, "
            f"'--real-rays', '--json'])\n"
            f"print([m for m in ('numba', 'cv2', 'OpenImageIO', 'rawpy', 'matplotlib', 'optiland') "
            f"if m in sys.modules])")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "[]"


def real_d(path):
    return g.real_ray_slices(Camera.from_toml(path), [1.0]).distance_mm[0]


def test_sidecars_of_a_prescription_camera_carry_the_real_rays(tmp_path):
    from lfproc.outputs import slice_metadata, write_views
    cam = Camera.from_toml(DG)
    meta = slice_metadata("x.png", cam, [1.0, 2.0])
    assert meta[0]["real_rays"] == g.real_ray_slices(cam, [1.0]).records()[0]
    assert "real_rays" not in slice_metadata("x.png", Camera.from_toml(CAMS / "paper-f100.toml"), [1.0])[0]
    keep = np.zeros((25, 25), bool)
    keep[0, 24] = True
    write_views(str(tmp_path), "cap", "cap.png", cam, np.zeros((25, 25, 4, 4, 1), np.float32), "png16", keep)
    side = json.loads(next(tmp_path.glob("*.json")).read_text())
    real = g.real_ray_views(cam, [-12, 12]).records()
    assert side["real_rays"] == {"position_mm": [real[0]["position_mm"], real[1]["position_mm"]],
                                 "tilt_deg": [real[0]["tilt_deg"], real[1]["tilt_deg"]]}


def test_zmx_reader_units_model_glasses_utf16_and_refusals(tmp_path):
    """A model-glass .zmx in inches and UTF-16 reads as the same lens as its inline table (no extra needed)."""
    lines = ["VERS 140101", "UNIT IN X W X CM MR CPMM", "SURF 0", "  DISZ INFINITY",
             "SURF 1", "  STOP", "  CURV " + repr(25.4 / 50.0), "  DISZ " + repr(8.0 / 25.4),
             "  GLAS ___BLANK 1 0 1.5 6.4E+1", "  DIAM 0.4",
             "SURF 2", "  CURV " + repr(-25.4 / 80.0), "  DISZ 1.0", "SURF 3", "  DISZ 0"]
    path = tmp_path / "thick.zmx"
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("utf-16"))
    lens = read_zmx(path, 587.6)
    ref = LensPrescription((Surface(50.0, 8.0, 1.5, stop=True), Surface(-80.0, 25.4, 1.0)))
    assert [s.index for s in lens.surfaces] == [1.5, 1.0] and lens.surfaces[0].semi_diameter_mm == pytest.approx(10.16)
    for key in ("focal_length_mm", "principal_plane_gap_mm", "exit_pupil_mm"):
        assert getattr(lens, key) == pytest.approx(getattr(ref, key), rel=1e-12)
    for bad, named in (("  TYPE EVENASPH", "EVENASPH"), ("  CONI -1.0", "conic"), ("  GLAS MIRROR", "mirror")):
        broken = tmp_path / "bad.zmx"
        broken.write_text("\n".join(lines[:8] + [bad] + lines[8:]) + "\n")
        with pytest.raises(LfprocError, match=named):
            read_zmx(broken, 587.6)
    with pytest.raises(LfprocError, match="not found"):
        read_zmx(tmp_path / "missing.zmx", 587.6)
    two_stops = LensPrescription.__new__(LensPrescription)
    with pytest.raises(LfprocError, match="exactly one surface"):
        two_stops.__init__((Surface(50.0, 8.0, 1.5, stop=True), Surface(-80.0, 25.4, 1.0, stop=True)))


SINGLET = """[sensor]
pixel_pitch_mm = 0.01
[mla]
pitch_mm = 0.25
focal_length_mm = 2.749
[main_lens]
focus_distance_mm = inf
[[main_lens.surfaces]]
radius_mm = 40.0
thickness_mm = 6.0
index = 1.5
stop = true
[[main_lens.surfaces]]
radius_mm = -40.0
thickness_mm = 0.0
[decode]
micro_image_px = 25
"""


def test_a_paraxial_distance_outside_the_real_dof_is_marked(tmp_path):
    """A fast biconvex singlet: near the lens its spherical aberration moves the DOF off the paraxial d_a."""
    path = tmp_path / "singlet.toml"
    path.write_text(SINGLET)
    cam = Camera.from_toml(path)
    para = g.slice_geometry(cam, np.array([1.0, 3.0]))
    real = g.real_ray_slices(cam, [1.0, 3.0])
    assert real.near_mm[0] <= para.distance_mm[0] <= real.far_mm[0]            # a = 1: inside
    assert not real.near_mm[1] <= para.distance_mm[1] <= real.far_mm[1]        # a = 3: outside
    assert np.all(real.near_mm <= real.distance_mm) and np.all(real.distance_mm <= real.far_mm)
    rows = run_cli("geometry", "--camera", path, "--a", "1,3", "--real-rays").stdout.splitlines()
    start = next(k for k, line in enumerate(rows) if line.startswith("distances from the sensor [mm]: paraxial"))
    assert not rows[start + 2].endswith("*") and rows[start + 3].endswith(" *")
    assert any(line.startswith("  * : the paraxial d_a lies outside") for line in rows)
