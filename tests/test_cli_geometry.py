"""`lfproc geometry`: the contract's JSON, the table, and a clean exit 2 for every bad camera file."""

import json
import math

import pytest

from conftest import SAMPLES, assert_clean_error, run_cli


def test_json_shape_and_values(paper_camera):
    proc = run_cli("geometry", "--camera", paper_camera, "--a", "0:2,3.5", "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)  # strict JSON: json.loads would accept Infinity, so check the text too
    assert "Infinity" not in proc.stdout and "NaN" not in proc.stdout
    assert set(data) >= {"slices", "views", "baseline_mm"}
    assert [s["a"] for s in data["slices"]] == [0.0, 1.0, 2.0, 3.5]
    for s in data["slices"]:
        assert set(s) >= {"a", "distance_mm", "near_mm", "far_mm", "dof_mm"}
    first = data["slices"][0]
    assert first["distance_mm"] is None and first["far_mm"] is None and first["dof_mm"] is None
    assert first["near_mm"] == pytest.approx(3483.2, abs=0.1)
    one = data["slices"][1]
    assert (one["near_mm"], one["distance_mm"], one["far_mm"]) == pytest.approx((301.538, 313.066, 325.596),
                                                                                abs=0.001)
    assert one["dof_mm"] == pytest.approx(24.058, abs=0.001)
    assert len(repr(one["distance_mm"])) > 10  # full double precision, not rounded
    views = data["views"]
    assert [v["i"] for v in views] == list(range(-12, 13))
    assert views[0]["position_mm"] == pytest.approx(4.344, abs=0.001) and views[0]["tilt_deg"] == 0.0
    assert data["baseline_mm"] == pytest.approx(0.362, abs=0.001)


def test_tilt_sign_follows_position_when_focused_near():
    proc = run_cli("geometry", "--camera", SAMPLES / "cameras" / "paper-f100-b20.toml", "--json")
    views = json.loads(proc.stdout)["views"]
    for v in views:
        assert math.copysign(1, v["tilt_deg"]) == math.copysign(1, v["position_mm"]) or v["i"] == 0
    assert abs(views[0]["tilt_deg"]) == pytest.approx(0.504, abs=0.002)


def test_table_default(paper_camera):
    proc = run_cli("geometry", "--camera", paper_camera)
    assert proc.returncode == 0, proc.stderr
    for text in ("301.538", "313.066", "325.596", "3483.222", "197.788", "0.3620", "pixel-limited"):
        assert text in proc.stdout
    assert proc.stdout.count("\n") > 10


def test_plot(paper_camera, tmp_path):
    out = tmp_path / "fig.png"
    proc = run_cli("geometry", "--camera", paper_camera, "--a", "0:5:0.5", "--plot", out)
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


BASE = (SAMPLES / "cameras" / "paper-f100.toml").read_text()


@pytest.mark.parametrize("mutate, mention", [
    (lambda t: t.replace("[mla]", "[mla"), "not valid TOML"),
    (lambda t: t.replace("[main_lens]", "[other]"), "missing table [main_lens]"),
    (lambda t: t.replace("pitch_mm = 0.25", 'pitch_mm = "wide"'), "mla.pitch_mm must be a number"),
    (lambda t: t.replace("pitch_mm = 0.25", "pitch_mm = -0.25"), "mla.pitch_mm must be a finite positive"),
    (lambda t: t.replace("image_distance_mm = 99.5145", "image_distance_mm = 90.0"), "beyond infinity"),
    (lambda t: t.replace("micro_image_px = 25", "micro_image_px = 24"), "odd integer"),
    (lambda t: t.replace('grid = "rectangular"', 'grid = "triangular"'), "unknown mla.grid"),
    (lambda t: t.replace("focal_length_mm = 2.749\n", ""), "missing mla.focal_length_mm"),
    (lambda t: t.replace("image_distance_mm = 99.5145", "focus_distance_mm = 150.0"), "closer than this lens"),
    (lambda t: t.replace("f_number = 4.0", "f_number = 0"), "f_number"),
    (lambda t: t.replace("principal_plane_gap_mm = -33.184", "principal_plane_gap = -33.184"),
     "unknown key 'principal_plane_gap' in [main_lens]"),
    (lambda t: "colour = 1\n" + t, "unknown key 'colour' in the top level"),
])
def test_bad_camera_files(tmp_path, mutate, mention):
    path = tmp_path / "bad.toml"
    path.write_text(mutate(BASE))
    assert_clean_error(run_cli("geometry", "--camera", path), str(path), mention)


def test_missing_camera_file(tmp_path):
    missing = tmp_path / "nope.toml"
    assert_clean_error(run_cli("geometry", "--camera", missing), str(missing), "not found")


@pytest.mark.parametrize("a_list", ["x", "0:5:0", "5:0:1", ""])
def test_bad_a_list(paper_camera, a_list):
    assert_clean_error(run_cli("geometry", "--camera", paper_camera, "--a", a_list), "--a")


def _all_lit_light_field(camera_path, path, lenses=(24, 32), channels=1):
    """Random texture with every view lit: refocus's sidecars then carry the DOF of --aperture's views alone."""
    import numpy as np

    from lfproc import Camera, LightField

    camera = Camera.from_toml(camera_path)
    m = camera.m_hat
    views = np.random.default_rng(5).random((m, m, *lenses, channels)).astype(np.float32)
    LightField.from_views(views, camera).save(path)
    return path


@pytest.mark.parametrize("camera_path,f_number,a_list", [
    (SAMPLES / "sample" / "camera.toml", "8", "0,0.5,1"),
    (SAMPLES / "cameras" / "lfm-20x.toml", "40", "-0.5,0,0.5"),
])
def test_geometry_aperture_gives_the_dof_refocus_tags(tmp_path, camera_path, f_number, a_list):
    """`lfproc geometry --aperture F` prints the near/far/DOF that `lfproc refocus --aperture F` writes into its
    sidecars for the same camera and a (and narrower than without it: the synthetic aperture is deeper)."""
    lf = _all_lit_light_field(camera_path, tmp_path / "lit.lfp.npz")
    proc = run_cli("refocus", lf, "--a", a_list, "--aperture", f_number, "-o", tmp_path / "r")
    assert proc.returncode == 0, proc.stderr
    sidecars = [json.loads(p.read_text()) for p in sorted((tmp_path / "r").glob("lit_*.json"), key=lambda p:
                                                          json.loads(p.read_text())["a"])]
    proc = run_cli("geometry", "--camera", camera_path, "--a", a_list, "--aperture", f_number, "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert len(data["slices"]) == len(sidecars) == 3
    for got, tags in zip(data["slices"], sidecars):
        for key, value in got.items():
            assert tags[key] == value, (key, got, tags)           # the same numbers, to the last bit
    full = json.loads(run_cli("geometry", "--camera", camera_path, "--a", a_list, "--json").stdout)["slices"]
    dof = "dof_um" if "dof_um" in full[1] else "dof_mm"
    assert data["slices"][1][dof] > 1.2 * full[1][dof]
    assert data["aperture"]["f_number"] == float(f_number)
    assert data["aperture"]["views_summed"] == sidecars[0]["views_summed"]
    table = run_cli("geometry", "--camera", camera_path, "--a", a_list, "--aperture", f_number).stdout
    assert f"synthetic aperture f/{f_number}: {sidecars[0]['views_summed']} views summed" in table
    near = "z_near_um" if "z_near_um" in full[1] else "near_mm"
    assert f"{sidecars[1][near]:.3f}" in table


def test_geometry_aperture_is_checked_and_light(tmp_path):
    camera = SAMPLES / "sample" / "camera.toml"
    assert_clean_error(run_cli("geometry", "--camera", camera, "--aperture", "2"), "wider than the main lens")
    assert_clean_error(run_cli("geometry", "--camera", camera, "--aperture", "100"), "narrower than one view")
    import subprocess
    import sys
    code = (f"import sys, io, contextlib; from lfproc.cli import main\n"
            f"with contextlib.redirect_stdout(io.StringIO()): main(['geometry', '--camera', {str(camera)!r}, "
            f"'--aperture', '8', '--json'])\n"
            f"print([m for m in ('numba', 'cv2', 'OpenImageIO', 'rawpy', 'matplotlib') if m in sys.modules])")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "[]"
