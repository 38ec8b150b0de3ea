"""The command line as a user meets it (issue 17): every command says what it did, agrees with the others,
and checks what it can before the first capture is decoded. Each test runs the command (``run_cli``: in this
process, one in a fresh interpreter) and checks the exit status and what it prints."""

import json
import math
import re
import shutil

import numpy as np
import pytest

from lfproc import Camera, geometry
from lfproc.cli import build_parser

from conftest import SAMPLES, assert_clean_error, run_cli

SAMPLE = SAMPLES / "sample"
SLICE_LINE = re.compile(r"^\s+a=([+-]\d+\.\d+)\s+([\d.]+) mm\s+in focus \[([\d.]+) mm, ([\d.]+|inf) mm\]$")


@pytest.fixture(scope="module")
def sample(tmp_path_factory, sample_grid):
    """The bundled sample, and its grid fitted once (so most tests decode without calibrating again)."""
    folder = tmp_path_factory.mktemp("cli")
    for name in ("capture.png", "white.png", "camera.toml"):
        shutil.copy(SAMPLE / name, folder / name)
    shutil.copy(sample_grid, folder / "grid.json")
    return folder


def decode_args(folder):
    return ["--camera", folder / "camera.toml", "--calib", folder / "grid.json", "--white", folder / "white.png"]


def test_refocus_prints_one_line_per_slice_with_distance_and_dof(sample, tmp_path):
    camera = Camera.from_toml(sample / "camera.toml")
    proc = run_cli("refocus", sample / "capture.png", *decode_args(sample), "--depth-range", "400:1300",
                   "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    rows = [SLICE_LINE.match(line) for line in proc.stdout.splitlines()]
    rows = [m for m in rows if m]
    written = sorted(p.name for p in tmp_path.glob("*.tif"))
    assert len(rows) == len(written) >= 2
    sidecars = sorted((json.loads(p.read_text()) for p in tmp_path.glob("*.json")), key=lambda d: d["a"])
    rows = sorted(rows, key=lambda m: float(m.group(1)))
    for m, side in zip(rows, sidecars):      # the printed numbers are the sidecars' (and the geometry's)
        assert float(m.group(1)) == pytest.approx(side["a"], abs=5e-5)
        geo = geometry.slice_geometry(camera, [side["a"]])
        assert side["distance_mm"] == pytest.approx(float(geo.distance_mm[0]), rel=1e-12)
        assert m.group(2) == f"{side['distance_mm']:.1f}"
        assert m.group(3) == f"{side['near_mm']:.1f}"
        assert m.group(4) == ("inf" if side["far_mm"] is None else f"{side['far_mm']:.1f}")
    assert "in focus over all of 400.0 mm..1300.0 mm" in proc.stdout
    assert "capture.png: " in proc.stdout and f"{len(written)} slice(s)" in proc.stdout
    assert "captures done" not in proc.stderr        # one capture: no summary line


def test_refocus_names_the_depths_it_leaves_uncovered(sample, tmp_path):
    proc = run_cli("refocus", sample / "capture.png", *decode_args(sample), "--depth-range", "400:1300",
                   "--integer", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    printed = sorted((float(lo), float(hi)) for lo, hi in
                     re.findall(r"no slice is in focus at ([\d.]+) mm\.\.([\d.]+) mm: a gap allowed by the integer",
                                proc.stdout))
    # the gaps, independently: the parts of 400..1300 mm outside every written slice's [near, far]
    sides = [json.loads(p.read_text()) for p in tmp_path.glob("*.json")]
    assert all(float(side["a"]).is_integer() for side in sides)
    spans = sorted((side["near_mm"], side["far_mm"] if side["far_mm"] is not None else float("inf")) for side in sides)
    gaps, reach = [], 400.0
    for lo, hi in spans:
        if lo > reach:
            gaps.append((reach, min(lo, 1300.0)))
        reach = max(reach, hi)
    if reach < 1300.0:
        gaps.append((reach, 1300.0))
    gaps = [(lo, hi) for lo, hi in gaps if hi > lo]
    assert len(printed) == len(gaps) >= 1
    for (plo, phi), (lo, hi) in zip(printed, gaps):
        assert plo == pytest.approx(lo, abs=0.06) and phi == pytest.approx(hi, abs=0.06)


@pytest.mark.parametrize("spelling", [["--a", "-0.4:0.6:0.2"], ["--a=-0.4:0.6:0.2"]])
def test_negative_a_lists_work_with_and_without_equals(sample, tmp_path, spelling):
    """Negative a are real slices when the main lens is focused nearer than infinity (here b_U = f_U + 2 mm:
    a_inf = -0.45); ``ls`` lists the slices in focus order, far to near, negatives first."""
    text = (sample / "camera.toml").read_text().replace("image_distance_mm = 50.0", "image_distance_mm = 52.0")
    (tmp_path / "near.toml").write_text(text)
    args = ["--camera", tmp_path / "near.toml", "--calib", sample / "grid.json", "--white", sample / "white.png"]
    proc = run_cli("refocus", sample / "capture.png", *args, *spelling, "-o", tmp_path / "o")
    assert proc.returncode == 0, proc.stderr
    names = sorted(p.stem for p in (tmp_path / "o").glob("*.tif"))
    assert names == [f"capture_{k:02d}_a{a:+.3f}" for k, a in enumerate((-0.4, -0.2, 0.0, 0.2, 0.4, 0.6))]


def test_geometry_accepts_a_negative_list_without_equals(paper_camera):
    proc = run_cli("geometry", "--camera", paper_camera, "--a", "-0.5:0.5:0.5", "--json")
    assert proc.returncode == 0, proc.stderr
    assert [s["a"] for s in json.loads(proc.stdout)["slices"]] == [-0.5, 0.0, 0.5]


def test_decoded_light_fields_are_inputs_of_refocus_views_and_batch(sample, tmp_path):
    lf_path = tmp_path / "cap.lfp.npz"
    proc = run_cli("decode", sample / "capture.png", *decode_args(sample), "-o", lf_path)
    assert proc.returncode == 0, proc.stderr
    direct = run_cli("refocus", sample / "capture.png", *decode_args(sample), "--a", "1", "-o", tmp_path / "direct")
    assert direct.returncode == 0, direct.stderr
    # no --camera, --calib or --white: the light field carries its camera and grid
    proc = run_cli("refocus", lf_path, "--a", "1", "-o", tmp_path / "r")
    assert proc.returncode == 0, proc.stderr
    from_lf = json.loads((tmp_path / "r" / "cap_00_a+1.000.json").read_text())
    assert from_lf["source"].endswith("cap.lfp.npz")
    assert from_lf["distance_mm"] == json.loads((tmp_path / "direct" / "capture_00_a+1.000.json").read_text())[
        "distance_mm"]
    from lfproc.io import read_image
    np.testing.assert_array_equal(read_image(tmp_path / "r" / "cap_00_a+1.000.tif"),
                                  read_image(tmp_path / "direct" / "capture_00_a+1.000.tif"))
    proc = run_cli("views", lf_path, "-o", tmp_path / "v")
    assert proc.returncode == 0, proc.stderr
    from lfproc import LightField
    lit = LightField.load(lf_path).view_mask        # the views that carry light: the only ones written
    m = Camera.from_toml(sample / "camera.toml").m_hat
    assert len(list((tmp_path / "v").glob("cap_view_*.tif"))) == (m * m if lit is None else int(lit.sum()))
    proc = run_cli("batch", lf_path, "--a", "0,1", "--workers", "1", "-o", tmp_path / "b")
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in (tmp_path / "b").glob("*.tif")) == ["cap_00_a+0.000.tif", "cap_01_a+1.000.tif"]


def test_batch_offers_every_per_capture_option_of_refocus_and_views(sample, tmp_path):
    proc = run_cli("batch", sample / "capture.png", *decode_args(sample), "--at", "650", "--upsample", "2",
                   "--views", "--mosaic", "--inside-aperture", "--workers", "1", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    camera = Camera.from_toml(sample / "camera.toml")
    a = float(geometry.refocus_parameter(camera, 650.0))
    slices = list(tmp_path.glob("capture_*_a*.tif"))
    assert len(slices) == 1 and slices[0].stem == f"capture_00_a{a:+.3f}"
    from lfproc.io import read_image
    ny, nx = read_image(slices[0]).shape[:2]
    views = sorted(tmp_path.glob("capture_view_*.tif"))
    vy, vx = read_image(views[0]).shape[:2]
    assert (ny, nx) == (2 * vy - 1, 2 * vx - 1)                       # --upsample 2
    assert json.loads(slices[0].with_suffix(".json").read_text())["upsample"] == 2   # and its sidecar says so
    inside = geometry.views_inside_aperture(camera)                  # --inside-aperture: lit views inside only
    written = {tuple(int(k) for k in p.stem.split("_")[-2:]) for p in views}
    c = camera.m_hat // 2
    assert (c, c) in written and all(inside[ky, kx] for ky, kx in written)
    assert all(read_image(p).max() > 0 for p in views)
    assert (tmp_path / "capture_views_mosaic.tif").is_file()           # --mosaic
    old = run_cli("batch", sample / "capture.png", *decode_args(sample), "--refocus", "1", "--workers", "1",
                  "-o", tmp_path / "old")
    assert old.returncode == 0, old.stderr                              # the old spelling still works


def _options_without_help(parser, path=()):
    import argparse
    missing = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                missing += _options_without_help(sub, path + (name,))
        elif action.help is None and not isinstance(action, argparse._HelpAction):
            missing.append(" ".join(path + (action.option_strings[0] if action.option_strings else action.dest,)))
    return missing


def test_every_option_of_every_command_has_help():
    assert _options_without_help(build_parser()) == []


def test_a_warning_is_one_plain_line(sample, tmp_path):
    grid = json.loads((sample / "grid.json").read_text())
    grid["white_image"] = str(tmp_path / "gone.png")           # the recorded white image is missing
    (tmp_path / "grid.json").write_text(json.dumps(grid))
    # in a fresh interpreter: what the first imports of numba, OpenCV and OpenImageIO may print counts too
    proc = run_cli("refocus", sample / "capture.png", "--camera", sample / "camera.toml", "--calib",
                   tmp_path / "grid.json", "--a", "0", "-o", tmp_path / "out", subprocess=True)
    assert proc.returncode == 0, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("lfproc refocus: warning: ") and "--white" in lines[0]
    assert "UserWarning" not in proc.stderr and "warnings.warn" not in proc.stderr


def test_demo_in_a_read_only_place_is_one_line(tmp_path):
    assert_clean_error(run_cli("demo", "-o", "/proc/lfproc-demo"), "/proc/lfproc-demo")


def test_output_folder_is_checked_before_any_capture_is_read(sample, tmp_path):
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not an image")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    # if the capture were read first, the error would name it; the folder must fail first
    assert_clean_error(run_cli("refocus", bad, *decode_args(sample), "--a", "0", "-o", blocker / "out"),
                       str(blocker))
    assert_clean_error(run_cli("views", bad, *decode_args(sample), "-o", "/proc/lfproc-out"), "/proc/lfproc-out")
    # decode's -o is a file: a folder given for it is refused before the capture is read, naming the fix
    assert_clean_error(run_cli("decode", bad, *decode_args(sample), "-o", tmp_path), str(tmp_path), "is a folder",
                       "capture.lfp.npz")


def test_duplicate_a_is_refused_before_decoding(sample, tmp_path):
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not an image")
    assert_clean_error(run_cli("refocus", bad, *decode_args(sample), "--a", "1,0,1", "-o", tmp_path / "o"),
                       "duplicate")
    assert not (tmp_path / "o").exists()


def test_one_slice_limit_for_lists_and_ranges_with_a_flag_beyond_it(sample, tmp_path):
    assert_clean_error(run_cli("refocus", sample / "capture.png", *decode_args(sample), "--a", "0:1:0.0001",
                               "-o", tmp_path), "10001 slices", "--max-slices")
    assert_clean_error(run_cli("refocus", sample / "capture.png", *decode_args(sample), "--a", "0:3",
                               "--max-slices", "3", "-o", tmp_path), "4 slices", "--max-slices")
    proc = run_cli("refocus", sample / "capture.png", *decode_args(sample), "--a", "0:3", "--max-slices", "4",
                   "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert not list(tmp_path.glob("*.tmp*"))


def test_one_failing_capture_is_one_line_several_get_a_summary(sample, tmp_path):
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not an image")
    assert_clean_error(run_cli("refocus", bad, *decode_args(sample), "--a", "0", "-o", tmp_path / "o"), str(bad))
    proc = run_cli("refocus", bad, sample / "capture.png", *decode_args(sample), "--a", "0", "-o", tmp_path / "o2")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 2 and str(bad) in lines[0] and "1 of 2 captures done" in lines[1]


def test_an_a_whose_refocused_area_is_under_half_is_refused_with_the_usable_range(sample, tmp_path):
    """Issue 20: a slice means something where its pixels average at least half of the summed views; an a
    where that area is under half the image is refused, with the usable range in a and distance, far end
    first (the old check offered "from 133.2 mm (a=+17.3) to 67.6 mm (a=-17.3)")."""
    from lfproc.lightfield import LightField
    from lfproc.refocusing import usable_a_bound
    camera = Camera.from_toml(sample / "camera.toml")
    proc = run_cli("decode", sample / "capture.png", *decode_args(sample), "-o", tmp_path / "cap.lfp.npz")
    assert proc.returncode == 0, proc.stderr
    lf = LightField.load(tmp_path / "cap.lfp.npz")
    mask = np.ones((lf.m_hat, lf.m_hat), bool) if lf.view_mask is None else lf.view_mask
    limit = usable_a_bound(mask, lf.lens_shape)
    c, (ny, nx) = lf.center_index, lf.lens_shape

    def refocused_area(a):
        """Brute force (contract: view k is read at j + a·(c − k)): pixels reached by >= half the summed views."""
        count = np.zeros((ny, nx))
        for ky, kx in zip(*np.nonzero(mask)):
            jy = np.arange(ny) + a * (c - ky)
            jx = np.arange(nx) + a * (c - kx)
            count += ((jy >= 0) & (jy <= ny - 1))[:, None] & ((jx >= 0) & (jx <= nx - 1))[None, :]
        return float((count >= 0.5 * mask.sum()).mean())

    assert refocused_area(limit * 0.999) >= 0.5 > refocused_area(limit * 1.001)
    assert refocused_area(-limit * 0.999) >= 0.5 > refocused_area(-limit * 1.001)
    proc = run_cli("refocus", tmp_path / "cap.lfp.npz", "--a", "400", "-o", tmp_path / "o")
    assert_clean_error(proc, "a=400", "mm")
    assert not (tmp_path / "o").exists()
    # the whole usable range, low-to-high in a: from the slice at infinity (a = 0, the lens focused at
    # infinity; not -limit, which focuses beyond it) to the area's bound, rounded inwards to 3 decimals
    assert geometry.infinity_parameter(camera) == 0.0
    printed = math.floor(limit * 1000 + 1e-6) / 1000
    assert 0 < limit - printed < 1e-3
    near = float(geometry.slice_distance_mm(camera, printed))
    text = f"usable: a from +0 (infinity) to {printed:+.3f}".rstrip("0") + f" ({near:.1f} mm)"
    assert text in proc.stderr, proc.stderr
    # just inside the usable range: written, with one plain warning line about the wide border band
    proc = run_cli("refocus", tmp_path / "cap.lfp.npz", "--a", f"{0.98 * limit:.3f}", "-o", tmp_path / "in")
    assert proc.returncode == 0, proc.stderr
    warning = [line for line in proc.stderr.splitlines() if "warning" in line]
    assert len(warning) == 1 and "fewer than half the pixels" in warning[0]
    proc = run_cli("refocus", tmp_path / "cap.lfp.npz", "--a", "1", "-o", tmp_path / "ok")
    assert proc.returncode == 0 and "warning" not in proc.stderr, proc.stderr


def test_slices_nearer_than_the_front_focal_plane_are_refused(sample, tmp_path):
    """Issue 20: on the sample (50 mm lens focused at infinity) --at 67 wrote a=-17.0114, 17 mm in front
    of the lens, and --a=-17 the same; nothing there forms a real image. --at is refused before decoding;
    a refusal of --a states the capture's one usable range (issue 38), the same as --a=400's."""
    camera = Camera.from_toml(sample / "camera.toml")
    front = camera.main_optics.sensor_path_mm(camera.mla_path_mm) + camera.main_optics.focal_length_mm
    assert 67 < front and geometry.slice_distance_mm(camera, -17.0) < front   # the model puts it there
    ranges = []
    for option in (["--at", "67"], ["--a=-17"], ["--a=400"]):
        proc = run_cli("refocus", sample / "capture.png", *decode_args(sample), *option, "-o", tmp_path / "o")
        assert_clean_error(proc, "front focal plane" if option[0] != "--a=400" else "only 0 %")
        assert not (tmp_path / "o").exists()
        ranges.append(proc.stderr.strip().split("usable: ")[-1])
    assert ranges[1] == ranges[2] and ranges[1].startswith("a from +0 (infinity) to +7.")   # one range
    # a slice beyond infinity is refused too (issue 30: it was written tagged "in focus [inf, inf]"), and a
    # sweep partly beyond it as a whole, before any slice is written, with the usable range low-to-high
    for option in (["--a=-0.3"], ["--a=-0.5:2"]):
        proc = run_cli("refocus", sample / "capture.png", *decode_args(sample), *option, "-o", tmp_path / "b")
        assert_clean_error(proc, "beyond infinity", ranges[1])
        assert not (tmp_path / "b").exists()


def test_batch_reads_lytro_captures_with_a_calibration_folder_and_no_camera_file(tmp_path):
    """Lytro files carry their camera; --white-dir picks the white image, in batch as in refocus."""
    lytro = SAMPLES / "lytro"
    args = ["--white-dir", lytro / "caldata", "--a", "0.25,1.25"]
    proc = run_cli("batch", lytro / "IMG_0001.lfr", *args, "--workers", "1", "-o", tmp_path / "b")
    assert proc.returncode == 0, proc.stderr
    assert "MOD_000" in proc.stderr and "metadata" in proc.stderr      # which white image, whose camera
    single = run_cli("refocus", lytro / "IMG_0001.lfr", *args, "-o", tmp_path / "r")
    assert single.returncode == 0, single.stderr
    from lfproc.io import read_image
    for name in ("IMG_0001_00_a+0.250", "IMG_0001_01_a+1.250"):
        np.testing.assert_array_equal(read_image(tmp_path / "b" / f"{name}.tif"),
                                      read_image(tmp_path / "r" / f"{name}.tif"))
        assert json.loads((tmp_path / "b" / f"{name}.json").read_text()) == \
            json.loads((tmp_path / "r" / f"{name}.json").read_text())


def test_float_tiffs_open_in_tifffile_and_opencv(sample, tmp_path):
    """Issue 17: the float32 outputs need no codec plug-in (OpenImageIO's default float predictor did)."""
    import cv2
    import tifffile
    from lfproc.io import read_image

    proc = run_cli("refocus", sample / "capture.png", *decode_args(sample), "--a", "1", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    path = tmp_path / "capture_00_a+1.000.tif"
    ours = read_image(path)
    np.testing.assert_array_equal(tifffile.imread(path), ours)
    np.testing.assert_array_equal(cv2.imread(str(path), cv2.IMREAD_UNCHANGED)[..., ::-1], ours)


def test_readme_command_table_lists_every_command():
    from conftest import ROOT
    from lfproc.cli import COMMANDS

    text = (ROOT / "README.md").read_text()
    table = text[text.index("## Commands"):text.index("`INPUT` is a capture")]
    listed = re.findall(r"^\| `lfproc (\w+)", table, re.M)
    assert listed == list(COMMANDS)


def test_a_truncated_png_is_one_line_without_the_libraries_own_messages(sample, tmp_path):
    """libpng reports a truncated file on stderr itself; lfproc's one line must be all the user sees."""
    cut = tmp_path / "cut.png"
    cut.write_bytes((sample / "capture.png").read_bytes()[:3000])
    assert_clean_error(run_cli("refocus", cut, *decode_args(sample), "--a", "1", "-o", tmp_path / "o"),
                       str(cut), "truncated or corrupt")
    assert_clean_error(run_cli("calibrate", cut, "--camera", sample / "camera.toml", "-o", tmp_path / "g.json"),
                       str(cut))


def test_slices_on_a_finer_grid_say_so_in_their_sidecars(tmp_path):
    """`--upsample S` refocuses on the (N − 1)·S + 1 grid: the sidecar, the embedded tags and the z-stack's
    records carry ``upsample``; slices on the lens grid carry no such key (the contract's sidecar unchanged)."""
    from lfproc import LightField
    from lfproc.io import read_image, read_metadata

    camera = Camera.from_toml(SAMPLES / "sample" / "camera.toml")
    views = np.random.default_rng(2).random((camera.m_hat, camera.m_hat, 20, 24, 1)).astype(np.float32)
    LightField.from_views(views, camera).save(tmp_path / "lit.lfp.npz")
    for upsample in ("1", "3"):
        out = tmp_path / f"u{upsample}"
        proc = run_cli("refocus", tmp_path / "lit.lfp.npz", "--a", "0.5", "--upsample", upsample, "--stack", "imagej",
                       "-o", out)
        assert proc.returncode == 0, proc.stderr
        image = out / "lit_00_a+0.500.tif"
        sidecar = json.loads(image.with_suffix(".json").read_text())
        s = int(upsample)
        assert read_image(image).shape[:2] == ((20 - 1) * s + 1, (24 - 1) * s + 1)
        assert sidecar.get("upsample") == (None if s == 1 else s)
        assert read_metadata(image) == sidecar
        import tifffile
        with tifffile.TiffFile(out / "lit_stack.tif") as tif:
            record = json.loads(tif.imagej_metadata["Info"])["slices"][0]
        assert record == sidecar
