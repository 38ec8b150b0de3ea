"""``lfproc info`` and ``lfproc camera`` on Lytro files, run as a user would; processed pictures refused."""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest

import lytrogen
from conftest import assert_clean_error, run_cli
from lfproc import Camera
from lfproc.io import write_image

CONTRACT_KEYS = {"format", "raw_light_field", "width", "height"}


@pytest.fixture
def illum_file(tmp_path):
    doc = lytrogen.illum_document(8, 6, modulation=False)
    return lytrogen.write_container(tmp_path / "IMG_0001.LFR", np.full((6, 8), 500), 10, "little",
                                    *lytrogen.frame_metadata_of(doc), modulation=False)


@pytest.fixture
def f01_pair(tmp_path):
    meta = lytrogen.f01_metadata(6, 4)
    return lytrogen.write_raw_pair(tmp_path / "frame.RAW", np.full((4, 6), 1000), 12, "big", meta, ".json")


def info_json(path):
    proc = run_cli("info", path, "--json")
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))


def test_info_json_of_a_container_has_the_contract_keys(illum_file):
    info = info_json(illum_file)
    assert CONTRACT_KEYS | {"camera_model", "sections"} <= set(info)
    assert (info["format"], info["raw_light_field"], info["width"], info["height"], info["camera_model"]) == \
        ("lytro-container", True, 8, 6, "B01")
    assert info["serial"] == "B5143909630" and info["cfa"] == "GRBG" and info["modulation_frame"] is False
    for section in info["sections"]:
        assert set(section) >= {"kind", "length", "sha1", "sha1_ok", "content"} and section["sha1_ok"] is True
    assert info["lens"]["focal_length_mm"] == pytest.approx(77.59365439414978)
    table = run_cli("info", illum_file)
    assert table.returncode == 0 and "raw sensor image (packed)" in table.stdout and "B5143909630" in table.stdout


def test_info_of_raw_pair_image_and_processed_picture(tmp_path, f01_pair):
    info = info_json(f01_pair)
    assert (info["format"], info["camera_model"], info["raw_light_field"], info["sections"]) == \
        ("lytro-raw", "F01", True, [])
    assert info["lens"]["exit_pupil_distance_mm"] is None     # infinite: null in strict JSON
    write_image(tmp_path / "cap.tif", np.zeros((4, 5), np.float32))
    info = info_json(tmp_path / "cap.tif")
    assert (info["format"], info["width"], info["height"], info["bits_per_pixel"]) == ("image", 5, 4, 32)
    stack = tmp_path / "IMG-stk.lfp"
    stack.write_bytes(lytrogen.processed_picture_bytes())
    info = info_json(stack)
    assert info["format"] == "lytro-container" and info["raw_light_field"] is False
    assert "processed Lytro picture" in info["content"] and len(info["sections"]) == 5


def test_info_of_a_truncated_container_is_a_clean_error(tmp_path, illum_file):
    cut = tmp_path / "cut.lfr"
    cut.write_bytes(illum_file.read_bytes()[:200])
    assert_clean_error(run_cli("info", cut), str(cut), "truncated")


def test_camera_file_from_metadata(tmp_path, illum_file):
    out = tmp_path / "camera.toml"
    proc = run_cli("camera", illum_file, "-o", out)
    assert proc.returncode == 0, proc.stderr
    cam = Camera.from_toml(out)
    provenance = dict(cam.provenance)
    assert provenance == tomllib.loads(out.read_text())["provenance"]
    fixture = lytrogen.fixture("illum-white-image.TXT")["master"]["picture"]["frameArray"][0]["frame"]["metadata"]
    devices = fixture["devices"]
    assert cam.pixel_pitch_mm == pytest.approx(devices["sensor"]["pixelPitch"] * 1e3, rel=1e-12)
    assert cam.mla_pitch_mm == pytest.approx(devices["mla"]["lensPitch"] * 1e3, rel=1e-12)
    assert cam.mla_focal_length_mm == pytest.approx(devices["mla"]["sensorOffset"]["z"] * 1e3, rel=1e-12)
    assert cam.main_optics.focal_length_mm == pytest.approx(devices["lens"]["focalLength"] * 1e3, rel=1e-12)
    assert cam.main_optics.f_number == pytest.approx(devices["lens"]["fNumber"])
    assert cam.main_optics.exit_pupil_distance_mm == pytest.approx(devices["lens"]["exitPupilOffset"]["z"] * 1e3)
    assert (cam.grid, cam.cfa, cam.black_level, cam.white_level) == ("hexagonal", "GRBG", 64, 1023)
    assert cam.main_optics.image_distance_mm == cam.main_optics.focal_length_mm     # default: focused at infinity
    assert cam.m_hat == 13                                       # 20 um / 1.4 um = 14.29 -> 13
    assert provenance["main_lens.image_distance_mm"].startswith("default: focused at infinity")
    assert provenance["mla.focal_length_mm"].startswith("metadata: devices.mla.sensorOffset.z")
    assert "rotation = -0.031648 deg" in out.read_text()      # -5.5236e-4 rad, as a comment


def test_camera_focus_distance_flag_and_telecentric_f01(tmp_path, illum_file, f01_pair):
    out = tmp_path / "camera.toml"
    assert run_cli("camera", illum_file, "-o", out, "--focus-distance", "1000").returncode == 0
    cam = Camera.from_toml(out)
    provenance = dict(cam.provenance)
    f_u, b_u = cam.main_optics.focal_length_mm, cam.main_optics.image_distance_mm
    z = 1000 - cam.mla_focal_length_mm - b_u                    # object distance from the (thin) main lens
    assert 1 / f_u == pytest.approx(1 / b_u + 1 / z, rel=1e-12)
    assert provenance["main_lens.image_distance_mm"].startswith("flag: --focus-distance 1000")
    assert run_cli("camera", f01_pair, "-o", out).returncode == 0
    cam = Camera.from_toml(out)
    assert math.isinf(cam.main_optics.exit_pupil_distance_mm) and cam.cfa == "BGGR" and cam.m_hat == 9


def test_camera_of_a_non_lytro_file_is_a_clean_error(tmp_path):
    write_image(tmp_path / "cap.png", np.zeros((4, 4), np.uint16))
    out = tmp_path / "camera.toml"
    assert_clean_error(run_cli("camera", tmp_path / "cap.png", "-o", out), "cap.png", "not a Lytro file")
    assert not out.exists()


@pytest.mark.parametrize("command", ["refocus", "views"])
def test_processed_picture_is_refused(tmp_path, command, paper_camera):
    from lfproc import simulate
    stack = tmp_path / "IMG-stk.lfp"
    stack.write_bytes(lytrogen.processed_picture_bytes())
    grid = simulate.default_grid(Camera.from_toml(paper_camera), (100, 100))
    (tmp_path / "grid.json").write_text(json.dumps(grid.to_json_dict()))
    out = tmp_path / "out"
    extra = ["--a", "0"] if command == "refocus" else []
    proc = run_cli(command, stack, "--camera", paper_camera, "--calib", tmp_path / "grid.json", "-o", out, *extra)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    errors = [line for line in proc.stderr.splitlines() if "error" in line]
    assert len(errors) == 1 and "holds no raw light field" in errors[0] and str(stack) in errors[0]
    assert not out.exists() or not any(out.iterdir())


def test_refocus_a_lytro_capture_with_its_calibration_folder(tmp_path):
    """The README's Lytro workflow on the bundled sample: no camera file, the white image picked by metadata."""
    from conftest import SAMPLES
    from lfproc import geometry
    from lfproc.cli.lytro_defaults import camera_for_captures

    capture = SAMPLES / "lytro" / "IMG_0001.lfr"
    out = tmp_path / "slices"
    proc = run_cli("refocus", capture, "--white-dir", SAMPLES / "lytro" / "caldata", "--a", "0.25,1.25", "-o", out)
    assert proc.returncode == 0, proc.stderr
    assert "camera from" in proc.stderr and "caldata/MOD_0000.RAW" in proc.stderr
    camera = camera_for_captures(None, [str(capture)])
    for k, a in enumerate((0.25, 1.25)):
        sidecar = json.loads((out / f"IMG_0001_{k:02d}_a+{a:.3f}.json").read_text())
        assert sidecar["source"] == str(capture.resolve()) and sidecar["a"] == a
        assert sidecar["distance_mm"] == pytest.approx(geometry.slice_distance_mm(camera, a), rel=1e-12)


def test_readme_lytro_workflow_with_the_camera_file(tmp_path):
    from conftest import SAMPLES
    capture, caldata = SAMPLES / "lytro" / "IMG_0001.lfr", SAMPLES / "lytro" / "caldata"
    assert run_cli("info", capture).returncode == 0
    assert run_cli("camera", capture, "-o", tmp_path / "lytro.toml").returncode == 0
    geometry = run_cli("geometry", "--camera", tmp_path / "lytro.toml", "--json")
    assert geometry.returncode == 0
    assert json.loads(geometry.stdout)["provenance"]["main_lens.image_distance_mm"].startswith("default")
    proc = run_cli("refocus", capture, "--camera", tmp_path / "lytro.toml", "--white-dir", caldata,
                   "--depth-range", "8000:60000", "-o", tmp_path / "lytro-slices")
    assert proc.returncode == 0, proc.stderr
    assert len(list((tmp_path / "lytro-slices").glob("*.json"))) >= 2


def _bad_lytro_inputs(tmp_path):
    """(file, what the one error line must say) for each kind of bad Lytro input."""
    dn = np.full((6, 8), 500)
    doc = lytrogen.illum_document(8, 6, modulation=False)
    good = lytrogen.container_bytes(lytrogen.pack10_little(dn), *lytrogen.frame_metadata_of(doc))
    truncated = tmp_path / "truncated.lfr"
    truncated.write_bytes(good[:-40])
    corrupt = tmp_path / "corrupt.lfr"
    corrupt.write_bytes(lytrogen.container_bytes(lytrogen.pack10_little(dn), *lytrogen.frame_metadata_of(doc),
                                                 bad_sha1=True))
    no_raw = tmp_path / "IMG-stk.lfp"
    no_raw.write_bytes(lytrogen.processed_picture_bytes())
    wrong_size = lytrogen.write_raw_pair(tmp_path / "size.RAW", dn, 10, "little", lytrogen.illum_document(8, 8))
    packing = lytrogen.illum_document(8, 6)
    packing["master"]["picture"]["frameArray"][0]["frame"]["metadata"]["image"]["rawDetails"]["pixelPacking"][
        "endianness"] = "big"
    unknown = lytrogen.write_raw_pair(tmp_path / "packing.RAW", dn, 10, "little", packing)
    return [(truncated, "truncated"), (corrupt, "fails its SHA-1 check"), (no_raw, "holds no raw light field"),
            (wrong_size, "but the raw data holds 60 bytes"), (unknown, "unknown raw packing")]


def test_bad_lytro_inputs_exit_2_with_one_line_and_write_nothing(tmp_path, paper_camera):
    from lfproc import simulate
    grid = simulate.default_grid(Camera.from_toml(paper_camera), (100, 100))
    write_image(tmp_path / "white.png", np.full((100, 100), 50000, np.uint16))
    (tmp_path / "grid.json").write_text(json.dumps(dict(grid.to_json_dict(), white_image=str(tmp_path / "white.png"))))
    for path, fragment in _bad_lytro_inputs(tmp_path):
        out = tmp_path / "out.lfp.npz"
        proc = run_cli("decode", path, "--camera", paper_camera, "--calib", tmp_path / "grid.json", "-o", out)
        assert_clean_error(proc, str(path), fragment)
        assert not out.exists() and not list(tmp_path.glob("*.tmp*"))


def test_camera_refuses_a_bad_output_before_reading_the_capture(tmp_path, illum_file):
    """`lfproc camera -o` is checked first, as every command's output: a folder, a path under a file, a folder
    that cannot be created; one line naming the path and the fix, nothing written."""
    (tmp_path / "plain").write_text("not a folder")
    cases = [(tmp_path, tmp_path, "is a folder", "camera.toml"),
             (tmp_path / "plain" / "camera.toml", tmp_path / "plain", "cannot write there", "-o CAMERA.toml"),
             (tmp_path / "plain" / "sub" / "camera.toml", tmp_path / "plain", "cannot write there", "-o CAMERA.toml")]
    for out, *mention in cases:
        assert_clean_error(run_cli("camera", illum_file, "-o", out), *mention)
    # the output is refused before the input is opened: a file that is no Lytro file is not even looked at
    assert_clean_error(run_cli("camera", tmp_path / "plain", "-o", tmp_path / "plain" / "c.toml"), "cannot write there")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["IMG_0001.LFR", "plain"]
    # a missing folder that can be created is fine
    assert run_cli("camera", illum_file, "-o", tmp_path / "new" / "camera.toml").returncode == 0


def test_export_refuses_a_bad_output_before_reading_the_pictures(tmp_path):
    import lytropics

    picture = lytropics.write(tmp_path / "IMG_0001-stk.lfp", lytropics.first_gen_stack())
    (tmp_path / "plain").write_text("not a folder")
    for out in (tmp_path / "plain", tmp_path / "plain" / "sub"):
        assert_clean_error(run_cli("export", picture, "-o", out), str(out), "cannot write there", "-o OUTDIR")
    # checked before any input: a text file given as the picture is not looked at yet
    assert_clean_error(run_cli("export", tmp_path / "plain", "-o", tmp_path / "plain" / "x"), "cannot write there")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["IMG_0001-stk.lfp", "plain"]


def test_camera_file_numbers_carry_no_binary_noise(tmp_path):
    """Metadata in metres written in millimetres: 3e-05 m is 0.03 mm in the file, not 0.030000000000000002
    (3e-05 * 1e3); every digit the metadata has stays; the notes print the metadata's float32 numbers rounded."""
    meta = lytrogen.f01_metadata(6, 4)
    devices = meta["devices"]
    devices["sensor"]["pixelPitch"] = 9e-06                         # 9e-06 * 1e3 = 0.009000000000000001
    devices["mla"]["lensPitch"] = 6e-05                             # 0.060000000000000005
    devices["mla"]["sensorOffset"]["z"] = 3e-05                     # 0.030000000000000002
    devices["lens"]["focalLength"] = 0.0064499998092651363          # float32 digits: kept as they are
    devices["lens"]["exitPupilOffset"]["z"] = 0.07
    devices["lens"]["infinityLambda"] = 7.300000190734863           # float32 7.3
    pair = lytrogen.write_raw_pair(tmp_path / "frame.RAW", np.full((4, 6), 1000), 12, "big", meta, ".json")
    out = tmp_path / "camera.toml"
    proc = run_cli("camera", pair, "-o", out)
    assert proc.returncode == 0, proc.stderr
    text = out.read_text()
    for line in ("pixel_pitch_mm = 0.009\n", "pitch_mm = 0.06\n", "focal_length_mm = 0.03\n",
                 "focal_length_mm = 6.449999809265136\n",                 # 0.006449999809265136 m, shifted
                 "exit_pupil_distance_mm = 70.0\n", "infinityLambda = 7.3\n"):
        assert line in text, (line, text)
    cam = Camera.from_toml(out)
    assert cam.main_optics.focal_length_mm == pytest.approx(0.0064499998092651363 * 1e3, rel=1e-15)
    assert (cam.pixel_pitch_mm, cam.mla_pitch_mm, cam.mla_focal_length_mm) == (0.009, 0.06, 0.03)
    assert "0000000" not in proc.stdout and "9999999" not in proc.stdout
