"""A microscope camera file runs through every command (issue 21): geometry, calibrate, decode, refocus,
views, depth, viewer and batch, with micrometre tags wherever a camera's would be millimetres.

The capture is a plain synthetic white/capture pair on a tiny telecentric lattice (independent generator
``whitegen``): what is checked here is the plumbing and the tags, not the optics (test_microscope_geometry).
"""

import json
import math

import numpy as np
import pytest
import tifffile

from lfproc import Camera

from conftest import SAMPLES, assert_clean_error, run_cli
from test_browser_viewer import _click_lens, assert_legend_labels_apart, browser  # noqa: F401  (the fixture)
from scopefile import TINY_LFM, write_tiny_lfm

CAMERA = TINY_LFM
SLICE_KEYS = {"source", "a", "z_um", "z_near_um", "z_far_um", "dof_um", "refocus_shifts", "provenance"}
SUMMED = {"views_summed"}   # where decoding delivers fewer than all views, their count (the DOF is theirs)


@pytest.fixture(scope="module")
def lfm(tmp_path_factory):
    folder = write_tiny_lfm(tmp_path_factory.mktemp("lfm"))
    proc = run_cli("calibrate", folder / "white.tif", "--camera", folder / "lfm.toml", "-o", folder / "grid.json")
    assert proc.returncode == 0, proc.stderr
    return folder


def _inputs(folder):
    return [folder / "capture.tif", "--camera", folder / "lfm.toml", "--calib", folder / "grid.json"]


def test_geometry_json_lists_slices_in_micrometres():
    proc = run_cli("geometry", "--camera", SAMPLES / "cameras" / "lfm-20x.toml", "--a", "0,0.1,-0.2", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert [set(s) for s in out["slices"]] == [{"a", "z_um", "z_near_um", "z_far_um", "dof_um"}] * 3
    zeta = 27 * 2433 * 1.33 / 400                                   # m̂·f_s·n/M², f_s in µm
    assert [s["z_um"] for s in out["slices"]] == pytest.approx([0.0, 0.1 * zeta, -0.2 * zeta], rel=1e-12)
    assert out["lateral_sampling_um"] == pytest.approx(6.25)
    assert {"i", "angle_deg", "inside_na"} == set(out["views"][0])
    assert out["camera"]["aplanatic"] is False
    table = run_cli("geometry", "--camera", SAMPLES / "cameras" / "lfm-60x-water.toml", "--z-range", "-5:5")
    assert table.returncode == 0 and "aplanatic (sine condition)" in table.stdout and "[µm]" in table.stdout


def test_geometry_z_range_plans_cover_or_step():
    cam = SAMPLES / "cameras" / "lfm-20x.toml"
    covered = json.loads(run_cli("geometry", "--camera", cam, "--z-range", "-30:40", "--json").stdout)["slices"]
    assert covered[0]["z_far_um"] <= -30 + 1e-6 and covered[-1]["z_near_um"] >= 40
    assert all(b["z_far_um"] <= a["z_near_um"] for a, b in zip(covered, covered[1:]))
    stepped = json.loads(run_cli("geometry", "--camera", cam, "--z-range", "-10:10:5", "--json").stdout)["slices"]
    assert [s["z_um"] for s in stepped] == pytest.approx([-10, -5, 0, 5, 10])


def test_a_z_step_far_finer_than_the_dof_is_warned_with_a_sensible_step():
    """Issue 32: a 0.2 um step against a 25 um DOF repeats each slice; the warning names half the DOF."""
    from lfproc import geometry
    cam_path = SAMPLES / "cameras" / "lfm-20x.toml"
    cam = Camera.from_toml(cam_path)
    ends = geometry.slice_geometry(cam, [geometry.position_parameter(cam, z) for z in (-10.0, 10.0)])
    dof = float(min(ends.z_near_um - ends.z_far_um))          # the thinnest DOF over the range, from its limits
    fine = dof / 40
    proc = run_cli("geometry", "--camera", cam_path, "--z-range", f"-10:10:{fine:.6g}", "--json")
    assert proc.returncode == 0, proc.stderr
    warnings = [line for line in proc.stderr.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "finer than the slices' depth of field" in warnings[0], proc.stderr
    assert f"about {dof / 2:.2g} µm" in warnings[0] and f"({dof:.3g} µm)" in warnings[0]
    for step in (dof / 2, dof / 9):                            # sensible steps: silent
        proc = run_cli("geometry", "--camera", cam_path, "--z-range", f"-10:10:{step:.6g}", "--json")
        assert proc.returncode == 0 and "warning" not in proc.stderr, proc.stderr


def test_bad_depth_options_are_one_line_errors(lfm):
    assert_clean_error(run_cli("refocus", *_inputs(lfm), "--depth-range", "100:200", "-o", lfm / "x"),
                       "--z-range")
    assert_clean_error(run_cli("geometry", "--camera", SAMPLES / "cameras" / "paper-f100.toml", "--z-range", "0:5"),
                       "--z-range", "µm from the native object plane", "--depth-range")
    assert_clean_error(run_cli("geometry", "--camera", lfm / "lfm.toml", "--disparity", "1"), "--disparity")
    assert_clean_error(run_cli("geometry", "--camera", lfm / "lfm.toml", "--z-range", "0:x"), "--z-range")
    assert not (lfm / "x").exists()


def test_refocus_decode_and_batch_tag_slices_in_micrometres(lfm):
    proc = run_cli("refocus", *_inputs(lfm), "--z-range", "-8:8:4", "-o", lfm / "refocus")
    assert proc.returncode == 0, proc.stderr
    sidecars = sorted((lfm / "refocus").glob("*.json"))
    assert len(sidecars) == 5
    tags = [json.loads(p.read_text()) for p in sidecars]
    assert all(set(t) - SUMMED == SLICE_KEYS and t["refocus_shifts"] == "paraxial" for t in tags)
    assert sorted(t["z_um"] for t in tags) == pytest.approx([-8, -4, 0, 4, 8])
    # issue 32: named by z, and `ls` (lexical order) lists them from low to high z
    assert [t["z_um"] for t in tags] == sorted(t["z_um"] for t in tags)
    # names write -0 as +0 (the slice at the native plane may be tagged z = -0.0)
    assert [p.stem for p in sidecars] == [f"capture_{k:02d}_z{t['z_um'] + 0.0:+.3f}um" for k, t in enumerate(tags)]
    with tifffile.TiffFile(str(sidecars[0].with_suffix(".tif"))) as tif:   # closed: no ResourceWarning later
        embedded = tif.pages[0].description
    assert json.loads(embedded)["z_um"] == pytest.approx(json.loads(sidecars[0].read_text())["z_um"])
    proc = run_cli("decode", *_inputs(lfm), "-o", lfm / "decoded.lfp.npz")
    assert proc.returncode == 0, proc.stderr
    proc = run_cli("batch", *_inputs(lfm), "--z-range", "-4:4", "--views", "-o", lfm / "batch")
    assert proc.returncode == 0, proc.stderr
    batch_tags = [json.loads(p.read_text()) for p in (lfm / "batch").glob("capture_*_z*um.json")]
    assert batch_tags and all(set(t) - SUMMED == SLICE_KEYS for t in batch_tags)
    # the batch's provenance names the same files as the command's, by absolute path (batch jobs are absolute)
    assert {k: v["sha256"] for k, v in batch_tags[0]["provenance"]["inputs"].items()} == \
        {k: v["sha256"] for k, v in tags[0]["provenance"]["inputs"].items()}
    assert list(tags[0]["provenance"]["inputs"]) == ["capture", "camera", "white", "grid"]


def test_views_carry_object_space_angles(lfm):
    proc = run_cli("views", *_inputs(lfm), "--mosaic", "-o", lfm / "views")
    assert proc.returncode == 0, proc.stderr
    # the outermost view of the central column that carries light (only those are written)
    ky = min(int(p.stem.split("_")[-2]) for p in (lfm / "views").glob("capture_view_*_03.json"))
    assert ky < 3
    tag = json.loads((lfm / "views" / f"capture_view_{ky:02d}_03.json").read_text())
    assert tag["view"] == [ky, 3] and tag["angle_deg"][1] == 0.0 and tag["angle_deg"][0] > 0
    assert tag["tilt_deg"] == tag["angle_deg"]
    # the contract's position_mm: where the view crosses the objective's pupil, f_obj·n·sin θ (Abbe sine condition)
    assert tag["position_mm"][1] == 0.0
    assert tag["position_mm"][0] == pytest.approx(180.0 / 20 * 1.33 * math.sin(math.radians(tag["angle_deg"][0])))
    sines = math.sin(math.radians(tag["angle_deg"][0])) * 1.33 / 20       # back to the image side (sine condition)
    u = (3 - ky) * 0.0475 / 7
    assert sines == pytest.approx(u / math.hypot(u, 0.95), rel=1e-9)


def test_depth_map_is_in_micrometres(lfm):
    proc = run_cli("depth", *_inputs(lfm), "--z-range", "-20:20", "-o", lfm / "depth")
    assert proc.returncode == 0, proc.stderr
    meta = json.loads((lfm / "depth" / "capture_depth.json").read_text())
    assert meta["unit"] == "um" and "native object plane" in meta["content"]
    depth = tifffile.imread(lfm / "depth" / "capture_depth.tif")
    known = depth[np.isfinite(depth)]
    assert known.size and np.all(np.abs(known) <= 40)      # within the searched range plus the padding
    assert not (lfm / "depth" / "capture_depth_points.ply").exists()
    assert "µm from the native object plane" in proc.stdout


def test_viewer_page_in_micrometres(lfm):
    proc = run_cli("viewer", *_inputs(lfm), "-o", lfm / "viewer")
    assert proc.returncode == 0, proc.stderr
    data = json.loads((lfm / "viewer" / "geometry.json").read_text())
    assert data["unit"] == "um" and all("z_um" in s and "distance_mm" not in s for s in data["slices"])
    assert all("angle_deg" in v for v in data["views"]["items"])
    assert "z_um" in data["depth"]["ticks"][0]


def test_viewer_page_reads_micrometres_in_the_browser(lfm, browser):
    from selenium.webdriver.support.ui import WebDriverWait

    out = lfm / "viewer-browser"
    proc = run_cli("viewer", *_inputs(lfm), "-o", out)
    assert proc.returncode == 0, proc.stderr
    data = json.loads((out / "geometry.json").read_text())
    browser.get((out / "index.html").as_uri())
    WebDriverWait(browser, 10).until(lambda d: d.execute_script("return document.body.dataset.ready === 'true'"))
    assert [e for e in browser.get_log("browser") if e["level"] == "SEVERE"] == []
    photo = browser.find_element("id", "photo")
    _click_lens(browser, photo, {"data": data}, data["lens_shape"][0] // 2, data["lens_shape"][1] // 2)
    here = browser.find_element("id", "here-distance").text
    assert here.endswith(" µm") or here == "unknown", here
    assert "µm" in browser.find_element("id", "slice-readout").text
    assert "native object plane" in browser.find_element("id", "depth-method").text
    # issue 32: a DOF reads from low to high z ("sharp from 1.71 µm to -1.71 µm" was backwards)
    import re
    ends = re.search(r"sharp from (-?[\d.]+) µm to (-?[\d.]+) µm", browser.find_element("id", "slice-readout").text)
    assert ends and float(ends.group(1)) < float(ends.group(2)), browser.find_element("id", "slice-readout").text
    assert_legend_labels_apart(browser)
