"""``lfproc simulate`` as a user runs it: a progress bar on a terminal, what it wrote, checks before rendering, and
the exit pupil and tilted planes of a scene file reaching the outputs."""

import fcntl
import json
import math
import os
import pty
import struct
import subprocess
import sys
import termios

import numpy as np

from lfproc.camera import Camera
from lfproc.grid import LensGrid

from conftest import assert_clean_error, run_cli

SCENE = """
background = 0.1
[camera]
[camera.sensor]
pixel_pitch_mm = 0.009
cfa = "RGGB"
[camera.mla]
pitch_mm = 0.1
focal_length_mm = 0.4
[camera.main_lens]
focal_length_mm = 50.0
image_distance_mm = 50.0
f_number = 4.0
[render]
height_px = 120
width_px = 160
{render}
[[plane]]
name = "ramp"
distance_mm = 800
texture = "noise"
feature_mm = 5.0
tilt_deg = [40, -10]
"""


def write_scene(tmp_path, render=""):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(render=render))
    return path


def run_on_a_terminal(*args):
    """Run ``python -m lfproc ARGS`` with stderr on a pseudo-terminal (as in a shell): (returncode, stdout, stderr)."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # a 100-column terminal
    proc = subprocess.Popen([sys.executable, "-m", "lfproc", *map(str, args)], stdout=subprocess.PIPE, stderr=slave,
                            env=os.environ)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 4096)
        except OSError:  # EIO: the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    stdout = proc.stdout.read().decode()
    proc.stdout.close()
    return proc.wait(timeout=600), stdout, b"".join(chunks).decode(errors="replace")


def test_simulate_shows_progress_on_a_terminal_and_lists_what_it_wrote(tmp_path):
    scene = write_scene(tmp_path)
    status, stdout, stderr = run_on_a_terminal("simulate", scene, "-o", tmp_path / "out")
    assert status == 0, stderr
    for stage in ("capture", "white image", "ideal views"):
        assert f"lfproc simulate ({stage})" in stderr
    assert "100%" in stderr
    lines = stdout.strip().splitlines()
    assert lines[0].startswith("lfproc simulate: rendered 120x160 px (RGGB mosaic, telecentric)")
    for name in ("capture.png", "white.png", "camera.toml", "ground_truth.npz", "ground_truth.json"):
        assert (tmp_path / "out" / name).is_file()
        assert any(line.strip().startswith(str(tmp_path / "out" / name)) for line in lines[1:]), name


def test_simulate_without_a_terminal_prints_no_bar(tmp_path):
    proc = run_cli("simulate", write_scene(tmp_path), "-o", tmp_path / "out")
    assert proc.returncode == 0 and proc.stderr == ""
    assert len(proc.stdout.strip().splitlines()) == 6


def test_unwritable_output_fails_before_rendering(tmp_path):
    scene = write_scene(tmp_path)
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if os.access(locked, os.W_OK):  # running as root: permissions do not bind, nothing to test
            return
        proc = run_cli("simulate", scene, "-o", locked / "out")
        assert_clean_error(proc, str(locked / "out"), "-o")
        assert not (locked / "out").exists()
    finally:
        locked.chmod(0o700)
    (tmp_path / "file").write_text("x")
    assert_clean_error(run_cli("simulate", scene, "-o", tmp_path / "file"), "not a folder")


def test_exit_pupil_and_tilt_reach_the_outputs(tmp_path):
    scene = write_scene(tmp_path, "exit_pupil_distance_mm = 30.0")
    proc = run_cli("simulate", scene, "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    assert "exit pupil 30 mm" in proc.stdout
    truth = json.loads((tmp_path / "out" / "ground_truth.json").read_text())
    scale = (30.0 + 0.4) / 30.0
    assert truth["exit_pupil_distance_mm"] == 30.0 and math.isclose(truth["micro_image_scale"], scale)
    assert truth["render"]["exit_pupil_distance_mm"] == 30.0
    grid, lenses = LensGrid.from_json_dict(truth["grid"]), LensGrid.from_json_dict(truth["lens_grid"])
    axis = np.array([(160 - 1) / 2, (120 - 1) / 2])
    np.testing.assert_allclose(grid.centers_xy_px() - axis, scale * (lenses.centers_xy_px() - axis), atol=1e-9)
    assert truth["planes"][0]["tilt_deg"] == [40.0, -10.0]
    assert Camera.from_toml(tmp_path / "out" / "camera.toml").main_optics.exit_pupil_distance_mm == 30.0
    depth = np.load(tmp_path / "out" / "ground_truth.npz")["depth_mm"]
    assert depth.shape == (grid.rows, grid.cols) and np.ptp(depth) > 10.0  # the tilted plane's depth varies


def test_telecentric_outputs_keep_their_format(tmp_path):
    """No exit pupil keys in ground_truth.json when telecentric: the files read exactly as before."""
    proc = run_cli("simulate", write_scene(tmp_path), "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    truth = json.loads((tmp_path / "out" / "ground_truth.json").read_text())
    assert not {"lens_grid", "exit_pupil_distance_mm", "micro_image_scale"} & set(truth)
    assert "exit_pupil_distance_mm" not in truth["render"]
