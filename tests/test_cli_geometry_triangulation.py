"""`lfproc geometry` run as a user would: triangulation (issue 12), the finite exit pupil, the JSON's
integer gaps and Airy check (issue 17), the plot, and the camera file's provenance (issue 11)."""

import json
import math

import pytest

from conftest import SAMPLES, assert_clean_error, run_cli
from focus import focused
from lfproc import Camera
from lfproc import geometry as g

ILLUM = SAMPLES / "cameras" / "illum-like.toml"


def test_triangulation_json_follows_the_contract():
    proc = run_cli("geometry", "--camera", ILLUM, "--disparity", "-1.5,0,0.25,2", "--gap", "-6", "--json")
    assert proc.returncode == 0, proc.stderr
    assert "Infinity" not in proc.stdout and "NaN" not in proc.stdout
    data = json.loads(proc.stdout)
    tri = data["triangulation"]
    assert [t["disparity_px"] for t in tri] == [-1.5, 0.0, 0.25, 2.0]
    cam = Camera.from_toml(ILLUM)
    for t in tri:
        assert set(t) >= {"gap", "disparity_px", "baseline_mm", "tilt_deg", "distance_mm"}
        assert t["gap"] == -6
        expected = g.triangulate(cam, t["disparity_px"], -6)
        assert t["baseline_mm"] == expected.baseline_mm and t["tilt_deg"] == expected.tilt_deg
        assert t["distance_mm"] == (None if math.isinf(expected.distance_mm) else expected.distance_mm)
    # a disparity of 0 between raw views is a point on slice a = 0: the focus distance, 1000 mm
    assert tri[1]["distance_mm"] == pytest.approx(1000.0, rel=1e-9)
    # B_G with PlenoptiSign's sign: G < 0 puts the second camera at positive heights
    assert tri[0]["baseline_mm"] > 0
    assert tri[0]["baseline_mm"] == pytest.approx(6 * data["baseline_mm"], rel=1e-12)


@pytest.mark.parametrize("spelling", [["--disparity", "-1,-0.5"], ["--disparity=-1,-0.5"]])
def test_negative_disparities_with_or_without_equals(spelling):
    proc = run_cli("geometry", "--camera", ILLUM, *spelling, "--gap", "2")
    assert proc.returncode == 0, proc.stderr
    section = proc.stdout.split("triangulation")[1].strip().splitlines()[2:4]
    assert [line.split()[:2] for line in section] == [["2", "-1"], ["2", "-0.5"]]


def test_negative_a_lists_with_or_without_equals():
    for args in (["--a", "-1:1"], ["--a=-1:1"]):
        proc = run_cli("geometry", "--camera", ILLUM, *args, "--json")
        assert proc.returncode == 0, proc.stderr
        assert [s["a"] for s in json.loads(proc.stdout)["slices"]] == [-1.0, 0.0, 1.0]


def test_table_names_the_exit_pupil_and_where_numbers_came_from():
    proc = run_cli("geometry", "--camera", ILLUM, "--disparity", "0.5")
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert "exit pupil 46.049 mm from the MLA" in out
    assert "where the camera's numbers came from:" in out
    assert "main_lens.exit_pupil_distance_mm: metadata: devices.lens.exitPupilOffset.z" in out
    assert "default: chosen for this example" in out
    assert "triangulation" in out and "pixel-limited" in out or "diffraction-limited" in out
    telecentric = run_cli("geometry", "--camera", SAMPLES / "cameras" / "paper-f100.toml").stdout
    assert "exit pupil at infinity (telecentric)" in telecentric and "came from" not in telecentric


def test_json_adds_integer_gaps_airy_check_camera_and_provenance(paper_camera):
    proc = run_cli("geometry", "--camera", paper_camera, "--a", "0:5", "--json")
    data = json.loads(proc.stdout)
    cam = Camera.from_toml(paper_camera)
    gaps = g.integer_slice_gaps(cam, range(6))
    assert gaps and [(x["a"], x["near_mm"], x["far_mm"]) for x in data["integer_gaps"]] == gaps
    table = run_cli("geometry", "--camera", paper_camera, "--a", "0:5").stdout
    for a, lo, hi in gaps:
        assert f"{lo:.3f} .. {hi:.3f} mm" in table
    check = g.diffraction_check(cam, warn=False)
    assert data["diffraction"]["pixel_limited"] is check.pixel_limited
    assert data["diffraction"]["micro_lens_airy_mm"] == pytest.approx(check.micro_lens_airy_mm, rel=1e-12)
    assert data["diffraction"]["message"] in table
    assert data["camera"]["telecentric"] is True and data["camera"]["exit_pupil_distance_mm"] is None
    assert data["camera"]["micro_image_scale"] == 1.0
    assert data["provenance"] == {}
    illum = json.loads(run_cli("geometry", "--camera", ILLUM, "--json").stdout)
    assert illum["provenance"]["mla.pitch_mm"] == "metadata: devices.mla.lensPitch"
    assert illum["camera"]["micro_image_scale"] == pytest.approx((46.049 + 0.0406) / 46.049, rel=1e-15)


def test_zero_gap_and_bad_disparity_are_clean_errors():
    assert_clean_error(run_cli("geometry", "--camera", ILLUM, "--disparity", "1", "--gap", "0"), "--gap")
    assert_clean_error(run_cli("geometry", "--camera", ILLUM, "--disparity", "x"), "--disparity")


def test_bad_provenance_is_a_clean_error(tmp_path):
    path = tmp_path / "cam.toml"
    path.write_text(ILLUM.read_text() + '"decode.micro_image_px" = 13\n')
    assert_clean_error(run_cli("geometry", "--camera", path), str(path), "provenance", "decode.micro_image_px")


def test_provenance_survives_a_round_trip_and_nested_keys():
    cam = Camera.from_toml(ILLUM)
    again = Camera.from_toml_string(cam.to_toml())
    assert again.provenance == cam.provenance and again == cam
    assert "[provenance]" not in cam.to_toml(include_provenance=False)
    refocused = focused(cam, 2000.0)                     # stale provenance of b_U is dropped
    assert refocused.provenance_of("main_lens.focus_distance_mm") is None
    assert refocused.provenance_of("mla.pitch_mm") == cam.provenance_of("mla.pitch_mm")
    nested = Camera.from_toml_string(ILLUM.read_text().split("[provenance]")[0]
                                     + "[provenance]\nmla.pitch_mm = \"metadata\"\n")
    assert nested.provenance == (("mla.pitch_mm", "metadata"),) and nested.provenance_of("mla.pitch_mm") == "metadata"


def test_plot_is_log_scaled_with_the_title_inside(tmp_path):
    from lfproc.plots import slice_figure
    cam = Camera.from_toml(SAMPLES / "cameras" / "paper-f100-b10.toml")
    fig = slice_figure(cam, g.slice_geometry(cam, [x / 2 for x in range(-1, 11)]))
    ax = fig.axes[0]
    assert ax.get_yscale() == "log" and fig.axes[1].get_yscale() == "log"
    renderer = fig.canvas.get_renderer()
    title = ax.title.get_window_extent(renderer)
    width, height = fig.canvas.get_width_height()
    assert 0 <= title.x0 and title.x1 <= width and title.y1 <= height
    # every finite DOF is drawn on the second panel
    finite = [r for r in g.slice_geometry(cam, [x / 2 for x in range(-1, 11)]).records() if math.isfinite(r["dof_mm"])]
    assert len(fig.axes[1].lines[0].get_xdata()) == len(finite)
    out = tmp_path / "fig.png"
    proc = run_cli("geometry", "--camera", ILLUM, "--a=-2:3:0.5", "--plot", out)
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_triangulation_command_stays_light():
    """`lfproc geometry` with a finite exit pupil and --disparity imports no numba/OpenCV/OIIO/matplotlib."""
    import subprocess
    import sys
    code = (f"import sys, io, contextlib; from lfproc.cli import main\n"
            f"with contextlib.redirect_stdout(io.StringIO()): main(['geometry', '--camera', {str(ILLUM)!r}, "
            f"'--disparity', '1', '--json'])\n"
            f"print([m for m in ('numba', 'cv2', 'OpenImageIO', 'rawpy', 'matplotlib') if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "[]"


def test_geometry_of_a_camera_written_from_lytro_metadata_says_where_numbers_came_from(tmp_path):
    """`lfproc camera` (lytro) writes [provenance]; `lfproc geometry` reads the file whole and prints it."""
    import numpy as np
    import lytrogen
    doc = lytrogen.illum_document(8, 6, modulation=False)
    lfr = lytrogen.write_container(tmp_path / "IMG_0001.LFR", np.full((6, 8), 500), 10, "little",
                                   *lytrogen.frame_metadata_of(doc), modulation=False)
    cam_file = tmp_path / "camera.toml"
    assert run_cli("camera", lfr, "-o", cam_file).returncode == 0
    cam = Camera.from_toml(cam_file)
    assert cam.provenance_of("main_lens.image_distance_mm").startswith("default: focused at infinity")
    assert not cam.telecentric
    proc = run_cli("geometry", "--camera", cam_file, "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert data["provenance"]["mla.focal_length_mm"].startswith("metadata: devices.mla.sensorOffset.z")
    table = run_cli("geometry", "--camera", cam_file).stdout
    assert "main_lens.image_distance_mm: default: focused at infinity" in table
