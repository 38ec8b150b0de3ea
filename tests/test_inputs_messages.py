"""Issue 30, smaller wrong messages: a folder given as the capture or the white image says it is a folder (not
"no such file"), and --white and --dark swapped names both files and the swap (not "the white image is black at
every lens centre", naming no file). Each: exit 2, one line, nothing written."""

import numpy as np
from conftest import SAMPLES, assert_clean_error, run_cli

SAMPLE = SAMPLES / "sample"
CAMERA = SAMPLE / "camera.toml"


def test_a_folder_as_the_capture_or_the_white_image_says_it_is_a_folder(tmp_path):
    folder = tmp_path / "shots"
    folder.mkdir()
    for command, extra in (("refocus", ("--a", "1")), ("views", ()), ("decode", ())):
        out = ("-o", tmp_path / "x.lfp.npz") if command == "decode" else ("-o", tmp_path / "out")
        proc = run_cli(command, folder, "--camera", CAMERA, "--white", SAMPLE / "white.png", *extra, *out)
        assert_clean_error(proc, str(folder), "is a folder")
        assert "no such file" not in proc.stderr
        proc = run_cli(command, SAMPLE / "capture.png", "--camera", CAMERA, "--white", folder, *extra, *out)
        assert_clean_error(proc, str(folder), "is a folder")
    proc = run_cli("calibrate", folder, "--camera", CAMERA, "-o", tmp_path / "g.json")
    assert_clean_error(proc, str(folder), "is a folder")
    assert not (tmp_path / "out").exists() and not (tmp_path / "g.json").exists()


def test_white_and_dark_swapped_name_both_files_and_the_swap(tmp_path):
    from PIL import Image

    rng = np.random.default_rng(0)
    dark = tmp_path / "dark.png"
    Image.fromarray((64 + rng.integers(0, 4, (600, 840))).astype(np.uint16)).save(dark)
    white = SAMPLE / "white.png"
    proc = run_cli("refocus", SAMPLE / "capture.png", "--camera", CAMERA, "--white", dark, "--dark", white,
                   "--a", "1", "-o", tmp_path / "out")
    assert_clean_error(proc, str(dark), str(white), "look swapped")
    proc = run_cli("calibrate", dark, "--camera", CAMERA, "--dark", white, "-o", tmp_path / "g.json")
    assert_clean_error(proc, str(dark), str(white), "look swapped")
    assert not (tmp_path / "out").exists() and not (tmp_path / "g.json").exists()
    proc = run_cli("calibrate", white, "--camera", CAMERA, "--dark", dark, "-o", tmp_path / "g.json")   # the right way
    assert proc.returncode == 0, proc.stderr
