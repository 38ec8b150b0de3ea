"""White (radiometry) images of light-field microscopes (issue 21): 8-bit and 16-bit whites rendered through
the objective's NA calibrate to the true lattice, and a pitch that contradicts the camera file is blamed on
the pixel size at the lenslets (relay magnification or pixel pitch), never on an exit pupil."""

import json
import re

import numpy as np
import pytest

from lfproc import Camera
from lfproc.simulate import render_microscope_sensor

from conftest import run_cli
from scopefile import microscope_toml

SENSOR = (280, 280)
RELAY = 0.7          # lens pitch 0.125 mm · 0.7 / 6.5 µm = 13.46 px


def camera_text(relay):
    return microscope_toml(name="lfm-white-test", relay=relay)


@pytest.fixture(scope="module")
def white():
    """The white image of the true microscope (relay 0.7): each micro image the NA's disk."""
    camera = Camera.from_toml_string(camera_text(RELAY))
    return camera, render_microscope_sensor(camera, None, SENSOR, pixel_samples=3, aperture_samples=1)


def write_white(path, image, bits):
    """An 8- or 16-bit PNG: a 5 % pedestal, the NA's disks at 95 % of full scale."""
    from PIL import Image

    top = 2 ** bits - 1
    Image.fromarray(np.round(0.05 * top + 0.9 * top * image).astype(np.uint8 if bits == 8 else np.uint16)).save(path)


@pytest.mark.parametrize("bits", [8, 16])
def test_white_calibrates_to_the_true_lattice(tmp_path, white, bits):
    camera, image = white
    (tmp_path / "cam.toml").write_text(camera_text(RELAY))
    write_white(tmp_path / "white.png", image, bits)
    proc = run_cli("calibrate", tmp_path / "white.png", "--camera", tmp_path / "cam.toml", "-o", tmp_path / "grid.json")
    assert proc.returncode == 0, proc.stderr
    assert "warning" not in proc.stderr, proc.stderr
    grid = json.loads((tmp_path / "grid.json").read_text())
    assert grid["pitch_px"] == pytest.approx(camera.pitch_px, abs=0.01)
    centres = np.array(grid["centers_xy_px"])
    axis = np.array([(SENSOR[1] - 1) / 2, (SENSOR[0] - 1) / 2])     # a lens sits on the sensor centre
    assert np.min(np.hypot(*(centres - axis).T)) < 0.05
    assert grid["implied_exit_pupil_distance_mm"] is None


def test_pitch_mismatch_names_the_relay_not_an_exit_pupil(tmp_path, white):
    """The camera file's relay 1.8 % low (the issue's real case): the warning gives the measured pitch and the
    relay magnification it implies, and says nothing of an exit pupil."""
    _, image = white
    (tmp_path / "cam.toml").write_text(camera_text(RELAY / 1.018))
    write_white(tmp_path / "white.png", image, 16)
    proc = run_cli("calibrate", tmp_path / "white.png", "--camera", tmp_path / "cam.toml", "-o", tmp_path / "grid.json")
    assert proc.returncode == 0, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if "warning" in line]
    assert len(lines) == 1, proc.stderr
    assert "exit pupil" not in lines[0]
    implied = float(re.search(r"microscope\.relay_magnification = ([\d.]+)", lines[0]).group(1))
    assert implied == pytest.approx(RELAY, abs=5e-4), lines[0]
    assert "13.46" in lines[0] and "+1.80 %" in lines[0], lines[0]
