"""Issue 23: the reader that fails decides the message, and cheap checks (every input's header, the output
path) run before the white image is calibrated."""

import time

import pytest
from conftest import SAMPLES, assert_clean_error, run_cli

SAMPLE = SAMPLES / "sample"
CAMERA = SAMPLE / "camera.toml"


@pytest.fixture
def text_tif(tmp_path):
    path = tmp_path / "notes.tif"
    path.write_text("these are my notes, not an image\n" * 20)
    return path


def test_a_text_file_named_tif_is_not_an_image_as_capture_white_or_dark(text_tif, tmp_path):
    for args in (("refocus", text_tif, "--white", SAMPLE / "white.png", "--a", "1", "-o", tmp_path / "a"),
                 ("calibrate", text_tif, "-o", tmp_path / "g.json"),
                 ("refocus", SAMPLE / "capture.png", "--white", text_tif, "--a", "1", "-o", tmp_path / "b"),
                 ("decode", SAMPLE / "capture.png", "--white", SAMPLE / "white.png", "--dark", text_tif,
                  "-o", tmp_path / "c.lfp.npz")):
        proc = run_cli(*args, "--camera", CAMERA)
        assert_clean_error(proc, str(text_tif), "not a readable image")
        assert "camera raw (" not in proc.stderr and "re-copy" not in proc.stderr   # not "corrupt camera raw"


def test_a_bad_capture_fails_before_the_white_image_is_calibrated(text_tif, monkeypatch, tmp_path):
    import lfproc.calibrate
    from lfproc.camera import Camera
    from lfproc.errors import LfprocError
    from lfproc.api import prepare_decoding

    def no_calibration(*args, **kwargs):
        raise AssertionError("the white image was calibrated before the inputs were checked")

    monkeypatch.setattr(lfproc.calibrate, "find_grid", no_calibration)
    camera = Camera.from_toml(CAMERA)
    for kwargs in ({"captures": [str(text_tif)]}, {"captures": [str(SAMPLE / "capture.png")], "dark": str(text_tif)}):
        with pytest.raises(LfprocError, match="not a readable image"):
            prepare_decoding(camera, white=str(SAMPLE / "white.png"), **kwargs, cache=True)


def test_calibrate_into_a_file_fails_before_any_work(tmp_path, monkeypatch):
    import lfproc.calibrate
    from lfproc.cli import main

    afile = tmp_path / "afile"
    afile.write_text("x")

    def no_work(*args, **kwargs):
        raise AssertionError("calibrated before checking where the grid goes")

    monkeypatch.setattr(lfproc.calibrate, "find_grid", no_work)
    assert main(["calibrate", str(SAMPLE / "white.png"), "--camera", str(CAMERA), "-o", str(afile / "grid.json")]) == 2
    start = time.perf_counter()
    proc = run_cli("calibrate", SAMPLE / "white.png", "--camera", CAMERA, "-o", afile / "grid.json")
    assert_clean_error(proc, str(afile), "-o GRID.json")
    assert "File exists" not in proc.stderr
    assert time.perf_counter() - start < 30


def test_decode_into_a_file_fails_before_decoding(tmp_path, monkeypatch):
    import lfproc.calibrate
    from lfproc.cli import main

    afile = tmp_path / "afile"
    afile.write_text("x")
    monkeypatch.setattr(lfproc.calibrate, "find_grid", lambda *a, **k: (_ for _ in ()).throw(AssertionError))
    for command in (["decode", str(SAMPLE / "capture.png"), "-o", str(afile / "x.lfp.npz")],
                    ["refocus", str(SAMPLE / "capture.png"), "--a", "1", "-o", str(afile / "out")],
                    ["views", str(SAMPLE / "capture.png"), "-o", str(afile / "out")]):
        assert main([*command, "--camera", str(CAMERA), "--white", str(SAMPLE / "white.png")]) == 2
