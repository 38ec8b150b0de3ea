"""Issue 20: a grid file records what it was made from, and every command checks camera, grid, white image
and capture against each other before decoding (one line naming both files and the differing value)."""

import json

import numpy as np
import pytest
from conftest import SAMPLES, assert_clean_error, run_cli
from lfproc.camera import MainLens

SAMPLE = SAMPLES / "sample"
CAMERA = SAMPLE / "camera.toml"


def test_the_grid_records_what_it_was_made_from(sample_grid):
    data = json.loads(sample_grid.read_text())
    for key in ("grid", "pitch_px", "rotation_deg", "residual_rms_px", "centers_xy_px"):   # contract keys stay
        assert key in data
    made = data["made_from"]
    assert made["camera"]["lens_pitch_px"] == pytest.approx(0.1 / 0.009)
    assert made["camera"]["pixel_pitch_mm"] == 0.009 and made["camera"]["lens_pitch_mm"] == 0.1
    assert made["camera"]["grid"] == "rectangular" and made["camera"]["m_hat"] == 11
    assert made["camera"]["micro_image_scale"] == 1.0 and made["camera"]["cfa"] == "RGGB"
    assert (made["white"]["width"], made["white"]["height"], made["white"]["cfa"]) == (840, 600, "RGGB")
    import hashlib
    assert made["white"]["hash"] == "sha256:" + hashlib.sha256((SAMPLE / "white.png").read_bytes()).hexdigest()
    assert made["dark"] is None
    assert 0 < data["pitch_sigma_px"] < 0.01


def test_a_grid_of_another_camera_is_refused(sample_grid, tmp_path):
    # the examples: exit 0 with 313.1 mm (paper-f100) and 11562.5 mm (a hexagonal Lytro camera) before
    proc = run_cli("refocus", SAMPLE / "capture.png", "--camera", SAMPLES / "cameras" / "paper-f100.toml",
                   "--calib", sample_grid, "--a", "1", "-o", tmp_path / "a")
    assert_clean_error(proc, str(sample_grid), "paper-f100.toml", "11.112 px", "25.000 px")
    proc = run_cli("views", SAMPLE / "capture.png", "--camera", SAMPLES / "cameras" / "illum-like.toml",
                   "--calib", sample_grid, "-o", tmp_path / "b")
    assert_clean_error(proc, str(sample_grid), "illum-like.toml", "rectangular", "hexagonal")
    proc = run_cli("batch", SAMPLE / "capture.png", "--camera", SAMPLES / "cameras" / "paper-f100.toml",
                   "--calib", sample_grid, "--a", "1", "-o", tmp_path / "c")
    assert_clean_error(proc, str(sample_grid), "paper-f100.toml", "25.000 px")
    proc = run_cli("viewer", SAMPLE / "capture.png", "--camera", SAMPLES / "cameras" / "illum-like.toml",
                   "--calib", sample_grid, "-o", tmp_path / "d")
    assert_clean_error(proc, str(sample_grid), "illum-like.toml", "hexagonal")
    assert not any((tmp_path / name).exists() for name in "abcd")


def test_the_right_camera_passes_and_old_sample_grids_still_load_and_are_checked(sample_grid, tmp_path):
    data = json.loads(sample_grid.read_text())
    for key in ("made_from", "pitch_sigma_px", "micro_image_scale", "micro_image_scale_sigma"):
        data.pop(key)
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data))
    proc = run_cli("refocus", SAMPLE / "capture.png", "--camera", CAMERA, "--calib", old, "--a", "1",
                   "-o", tmp_path / "ok")
    assert proc.returncode == 0, proc.stderr
    assert "668.6 mm" in proc.stdout
    # 3 % off: within what lfproc calibrate accepts (5 %) for a grid without a record, refused with one
    camera = tmp_path / "off.toml"
    camera.write_text(CAMERA.read_text().replace("pitch_mm = 0.1\n", "pitch_mm = 0.103\n"))
    proc = run_cli("decode", SAMPLE / "capture.png", "--camera", camera, "--calib", sample_grid,
                   "-o", tmp_path / "x.lfp.npz")
    assert_clean_error(proc, str(sample_grid), "off.toml", "11.444 px", "-2.9 %")
    from lfproc.camera import Camera
    from lfproc.grid import LensGrid
    from lfproc.inputs import check_grid_fits_camera
    check_grid_fits_camera(Camera.from_toml(camera), LensGrid.load(old))   # old file: accepted


def test_the_exit_pupil_scale_is_part_of_the_predicted_pitch(tmp_path):
    """The micro image pitch is the lens pitch x (d_A + f_s)/d_A: a grid of a camera with a finite exit pupil
    fits that camera file and is refused by the same camera called telecentric, and vice versa."""
    from lfproc.camera import Camera
    import dataclasses

    from lfproc.grid import Calibration, LensGrid
    from lfproc.inputs import check_grid_fits_camera
    from lfproc.errors import LfprocError

    near = Camera(0.0014, 0.02, 0.4, MainLens(50.0, 50.0, f_number=2.0, exit_pupil_distance_mm=20.0), grid="hexagonal")
    far = Camera(0.0014, 0.02, 0.4, MainLens(50.0, 50.0, f_number=2.0), grid="hexagonal")
    scale = (20.0 + 0.4) / 20.0                                      # 2 % wider micro image lattice
    old = LensGrid("hexagonal", near.pitch_px * scale, 0.0, (5.0, 5.0), 10, 10,
                   calibration=Calibration(made_from=None, pitch_sigma_px=1e-4), source="g.json")
    check_grid_fits_camera(near, old)                                 # old grid: 5 % accepted either way
    check_grid_fits_camera(far, old)
    recorded = {"camera": {"lens_pitch_px": near.pitch_px, "micro_image_scale": scale, "grid": "hexagonal"}}
    fitted = dataclasses.replace(old, calibration=Calibration(made_from=recorded, pitch_sigma_px=1e-4))
    check_grid_fits_camera(near, fitted)
    with pytest.raises(LfprocError, match="belongs to another camera"):
        check_grid_fits_camera(far, fitted)                           # 2 % > the 1 % floor, not the recorded camera


def test_sensor_size_and_bayer_pattern_must_match(sample_grid, tmp_path):
    from PIL import Image
    crop = tmp_path / "crop.png"
    Image.fromarray(np.asarray(Image.open(SAMPLE / "capture.png"))[:400, :600]).save(crop)
    proc = run_cli("refocus", crop, "--camera", CAMERA, "--calib", sample_grid, "--a", "1", "-o", tmp_path / "a")
    assert_clean_error(proc, str(crop), "600x400", "840x600")
    bggr = tmp_path / "bggr.toml"
    bggr.write_text(CAMERA.read_text().replace('cfa = "RGGB"', 'cfa = "BGGR"'))
    proc = run_cli("depth", SAMPLE / "capture.png", "--camera", bggr, "--calib", sample_grid, "-o", tmp_path / "b")
    assert_clean_error(proc, "BGGR", "RGGB", str(sample_grid), str(bggr))
    proc = run_cli("refocus", SAMPLE / "capture.png", "--camera", CAMERA, "--white", crop, "--a", "1",
                   "-o", tmp_path / "c")    # a white image of another size than the capture, before calibrating
    assert_clean_error(proc, str(crop), "600x400", "840x600")


def test_a_damaged_provenance_record_is_one_error_not_a_crash(sample_grid, tmp_path):
    from lfproc.errors import LfprocError
    from lfproc.grid import LensGrid

    data = json.loads(sample_grid.read_text())
    good = data["made_from"]
    for bad in (1, {"camera": 1}, {**good, "camera": {**good["camera"], "lens_pitch_px": "11"}},
                {**good, "white": {**good["white"], "channels": [1]}}, {**good, "dark": {"path": [1], "hash": "x"}},
                {**good, "dark": [1]}):
        path = tmp_path / "bad.json"
        path.write_text(json.dumps(dict(data, made_from=bad)))
        with pytest.raises(LfprocError, match="made_from"):
            LensGrid.load(path)
