"""Issue 38, the first hour on one's own data, on generated files: geometry with the grid equals the sidecars,
warnings once per call and the same in Python, messages that name the fix, no library text on stderr, depth
previews that read. The same situations on the real files: tests/real/test_real_first_hour.py."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
import tifffile

import lfproc
from conftest import SAMPLES, assert_clean_error, run_cli
from scopefile import microscope_toml, write_tiny_lfm

#: the tiny microscope of `write_tiny_lfm` with a relay 4.3 % too low: nominal 6.99 px a lens (m̂ 5), measured
#: 7.31 px (m̂ 7), as the sea urchin's metadata says 16.89 px (m̂ 15) where its white image measures 17.20 (m̂ 17)
OFF_RELAY = microscope_toml(name="tiny-lfm-off", pitch=0.0475, f_s=0.95, grid=None, wavelength=510, relay=0.957)
SLICE_KEYS = ("a", "z_um", "z_near_um", "z_far_um", "dof_um", "views_summed")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    folder = write_tiny_lfm(tmp_path_factory.mktemp("tiny"))
    (folder / "off.toml").write_text(OFF_RELAY)
    proc = run_cli("calibrate", folder / "white.tif", "--camera", folder / "off.toml", "-o", folder / "grid.json")
    assert proc.returncode == 0, proc.stderr
    assert "relay_magnification" in proc.stderr            # the measured pitch is not the nominal one
    return folder


def _sidecars(folder):
    return sorted((json.loads(p.read_text()) for p in folder.glob("capture_*.json")), key=lambda r: r["a"])


def _assert_same_slices(got, want):
    assert len(got) == len(want) > 0
    for g, w in zip(got, want):
        for key in SLICE_KEYS:
            assert g[key] == pytest.approx(w[key], rel=1e-9, abs=1e-12), (key, g, w)


@pytest.mark.parametrize("slices", [("--a", "-0.3,0,0.2,0.5"), ("--z-range", "-10:10:5")])
def test_geometry_with_the_grid_equals_the_refocus_sidecars(tiny, tmp_path, slices):
    """The issue saw 12 % between geometry's z table (nominal m̂) and the sidecars (measured m̂) of the same a."""
    proc = run_cli("refocus", tiny / "capture.tif", "--camera", tiny / "off.toml", "--calib", tiny / "grid.json",
                   *slices, "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    sidecars = _sidecars(tmp_path / "out")
    proc = run_cli("geometry", "--camera", tiny / "off.toml", "--calib", tiny / "grid.json", *slices, "--json")
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    assert report["camera"]["m_hat"] == 7
    _assert_same_slices(report["slices"], sidecars)
    nominal = run_cli("geometry", "--camera", tiny / "off.toml", *slices, "--json")
    notes = [line for line in nominal.stderr.splitlines() if "note" in line]
    assert len(notes) == 1 and "m̂ 5 is the camera file's nominal one" in notes[0] and "--calib" in notes[0]
    assert json.loads(nominal.stdout)["camera"]["m_hat"] == 5


def test_the_python_route_to_the_sidecars_numbers(tiny, tmp_path):
    """A light field carries the measured m̂ and the views it sums: the geometry of lf.camera with
    summed_view_extent(lf.view_mask) is what focal_stack tags (docs/microscope.md)."""
    from lfproc import geometry

    lf = lfproc.read_light_field(tiny / "capture.tif", tiny / "off.toml", grid=tiny / "grid.json")
    a = [-0.3, 0.0, 0.2, 0.5]
    records = geometry.slice_geometry(lf.camera, a, geometry.summed_view_extent(lf.view_mask)).records()
    tagged = lfproc.focal_stack(lf, a=a).records()
    for key in SLICE_KEYS[:5]:
        assert [r[key] for r in records] == pytest.approx([r[key] for r in tagged], rel=1e-12)


def test_a_fine_z_step_is_said_once_on_the_command_line_and_in_python(tiny, tmp_path):
    """The CLI printed the z-step advice twice (planned, then again for the decoded light field); Python none."""
    proc = run_cli("refocus", tiny / "capture.tif", "--camera", tiny / "off.toml", "--calib", tiny / "grid.json",
                   "--z-range", "-5:5:0.05", "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    said = [line for line in proc.stderr.splitlines() if "finer than the slices' depth of field" in line]
    assert len(said) == 1, proc.stderr
    lf = lfproc.read_light_field(tiny / "capture.tif", tiny / "off.toml", grid=tiny / "grid.json")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lfproc.focal_stack(lf, z_um=np.arange(-5.0, 5.0001, 0.05))
    advice = [str(w.message) for w in caught if "finer than" in str(w.message)]
    assert len(advice) == 1 and issubclass(caught[0].category, lfproc.LfprocWarning)
    assert said[0] == f"lfproc refocus: warning: {advice[0]}"              # the same words
    assert "µm" in advice[0] and " um" not in advice[0]


# ----------------------------------------------------------------------------- messages
def test_a_camera_file_of_another_sensor_names_the_camera_file(tmp_path):
    """The issue: "the camera's sensor.white_level 16383 exceeds this 8-bit file's maximum 255; set
    sensor.white_level", for the bundled sample's camera file on an 8-bit capture: the fix is the right file."""
    white = tmp_path / "radiometry.tif"
    tifffile.imwrite(white, np.full((64, 64), 140, np.uint8))
    camera = SAMPLES / "sample" / "camera.toml"
    proc = run_cli("calibrate", white, "--camera", camera, "-o", tmp_path / "grid.json")
    assert_clean_error(proc, str(white), str(camera), "an 8-bit file", "describes another camera", "--camera",
                       "saturates at 16383")
    with pytest.raises(lfproc.LfprocError, match=r"describes another camera; pass camera= the camera of the "):
        lfproc.calibrate_white(white, camera)


#: the fuzz fixture (../shared/fixtures/fuzz/tiff-ifd-stripbytecounts.tif): tifffile's 96 x 128 uint16 TIFF with
#: bytes 31 (StripByteCounts' type and count) and 120 changed
DAMAGED_IFD = ((31, 0xDA), (120, 0x37))


def _tiff_bytes(changes=()) -> bytes:
    import io

    buffer = io.BytesIO()
    tifffile.imwrite(buffer, np.zeros((96, 128), np.uint16))
    data = bytearray(buffer.getvalue())
    for offset, value in changes:
        data[offset] = value
    return bytes(data)


def test_a_tiff_with_a_damaged_ifd_gives_one_line_and_no_library_text(tmp_path):
    """LibRaw printed "FILE: Unexpected end of file" before lfproc's line (the fourth escape of this class)."""
    path = tmp_path / "damaged.tif"
    path.write_bytes(_tiff_bytes(DAMAGED_IFD))
    for command in (("info", path), ("calibrate", path, "--camera", SAMPLES / "sample" / "camera.toml", "-o",
                                     tmp_path / "grid.json")):
        assert_clean_error(run_cli(*command), str(path), "not a readable image")


def test_no_reader_prints_to_stderr_for_any_damaged_byte_of_the_ifd(tmp_path, capfd):
    """The class, not the file: every byte of the header and the IFD changed to a few values, read in this
    process by every reader; nothing reaches file descriptor 2, and every refusal is one line."""
    from lfproc.io import describe_file, read_capture, read_metadata

    clean = _tiff_bytes()
    ifd_end = 8 + 2 + 12 * clean[8] + 4
    path = tmp_path / "capture.tif"
    for offset in range(ifd_end):
        for value in {0x00, 0xFF, clean[offset] ^ 0x5A}:
            path.write_bytes(clean[:offset] + bytes([value]) + clean[offset + 1:])
            for read in (describe_file, read_capture, read_metadata):
                try:
                    read(path)
                except lfproc.LfprocError as exc:
                    assert "\n" not in str(exc)
            err = capfd.readouterr().err
            assert err == "", (offset, value, err)


@pytest.mark.parametrize("content, says", [
    ({"calibrate": {"ulens_pitch": 125}}, "napari-LF's metadata"),
    ({"pitch_px": 11.1, "lattice": "rectangular"}, "GRID.json"),
    ({"source": "capture.png", "a": 0.5}, "sidecar"),
    ({"anything": 1}, "a JSON file, not an image")])
def test_info_on_a_json_file_says_what_it_is_without_library_internals(tmp_path, content, says):
    path = tmp_path / "file.json"
    path.write_text(json.dumps(content))
    proc = run_cli("info", path)
    assert_clean_error(proc, str(path), says)
    assert "OpenImageIO" not in proc.stderr and "LibRaw" not in proc.stderr


# ----------------------------------------------------------------------------- pictures
def test_depth_ticks_sit_at_round_values_of_the_unit():
    from lfproc.depth._preview import _z_scale, round_ticks

    for lo, hi in ((-0.1742, 61.0), (-56.53, 99.36), (0.3, 0.34), (-12345.6, 12000.0), (3.0, 3.0001)):
        ticks, step = round_ticks(lo, hi)
        assert 3 <= len(ticks) <= 10 and all(lo <= t <= hi for t in ticks)
        mantissa = step / 10 ** np.floor(np.log10(step))
        assert round(mantissa, 9) in (1.0, 2.0, 5.0)
        assert all(abs(t / step - round(t / step)) < 1e-9 for t in ticks)
    z = np.linspace(-0.1742, 61.0, 400).reshape(20, 20)          # shown: its 1st to 99th percentile, 0.44-60.4
    _, ticks, title = _z_scale(z)
    assert title == "z (µm)" and [label for _, label in ticks] == [f"+{v} µm" for v in range(10, 70, 10)]


def test_the_preview_tells_no_light_from_unknown_depth():
    """The sea urchin's preview was 93 % grey: 64 % of its lenses get no light. Unlit lenses are black, lit
    ones of unknown depth grey, and the legend says which is which."""
    from lfproc.colours import UNKNOWN_COLOUR
    from lfproc.depth._preview import NO_LIGHT_RGB, TARGET_SIZE_PX, preview_image

    z = np.full((24, 24), np.nan)
    z[8:16, 8:16] = np.linspace(-20.0, 20.0, 64).reshape(8, 8)
    unlit = np.ones(z.shape, bool)
    unlit[4:20, 4:20] = False                         # lit: the known square and a grey ring around it
    scale = round(TARGET_SIZE_PX / 24)
    body = preview_image(None, z_um=z, unlit=unlit)[10:10 + 24 * scale, :24 * scale]
    centre = lambda r, c: tuple(body[r * scale + scale // 2, c * scale + scale // 2])   # noqa: E731
    assert centre(0, 0) == NO_LIGHT_RGB and centre(5, 5) == UNKNOWN_COLOUR and centre(10, 10) not in \
        (NO_LIGHT_RGB, UNKNOWN_COLOUR)


# ----------------------------------------------------------------------------- real-data tests anywhere
def test_the_real_data_tests_follow_lfproc_real_data_and_docs_count_them(tmp_path):
    """`LFPROC_REAL_DATA` points tests/real at a copy of the real data; without it they all skip, and
    docs/real-data.md and the README say how many."""
    import os
    import re
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, LFPROC_REAL_DATA=str(tmp_path / "nowhere"))
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "0",
                           "-rs", str(root / "tests" / "real")], capture_output=True, text=True, env=env, cwd=root)
    skipped = re.search(r"(\d+) skipped", proc.stdout)
    assert proc.returncode == 0 and skipped and " passed" not in proc.stdout, proc.stdout[-2000:]
    assert f"{tmp_path / 'nowhere'}: the real data folder is absent; set LFPROC_REAL_DATA" in proc.stdout
    for page in ("docs/real-data.md", "README.md"):
        stated = re.search(r"without them its\s+(\d+) tests skip", (root / page).read_text())
        assert stated and int(stated.group(1)) == int(skipped.group(1)), page
