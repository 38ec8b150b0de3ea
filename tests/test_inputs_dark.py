"""Issue 21: ``--dark FILE`` is subtracted per pixel (after the same level mapping) from captures and white
images, recorded in the grid file, and part of a batch's fingerprint."""

import json
import os

import numpy as np
import pytest
from conftest import assert_clean_error, run_cli
from PIL import Image

from lfproc.camera import Camera, MainLens
from lfproc.api import prepare_decoding

# an 8-bit monochrome camera (the sample's optics): a pedestal of 16-24 DN is 6-9 % of its range
CAM = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), grid="rectangular", cfa="none", black_level=0, white_level=255, micro_image_px=11)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A textured plane on the left, black on the right; capture and white with and without a pedestal."""
    from lfproc.simulate import Noise, Plane, Scene, render
    sim = render(CAM, Scene((Plane(800.0, Noise(6.0, low=0.3, high=0.9), region_mm=(-1e3, 0.0, -1e3, 1e3)),),
                            background=0.0), (264, 352), rotation_deg=0.3, ideal_views=False, pixel_samples=2,
                 aperture_samples=2)
    folder = tmp_path_factory.mktemp("dark")
    dark = np.round(16 + 8 * np.mgrid[0:264, 0:352][1] / 352).astype(np.uint8)   # a pedestal with a gradient

    def write(name, array):
        Image.fromarray(np.clip(array, 0, 255).astype(np.uint8)).save(folder / name)
        return str(folder / name)

    (folder / "camera.toml").write_text(CAM.to_toml())
    return dict(folder=folder, camera=str(folder / "camera.toml"),
                clean=write("clean.png", sim.raw), clean_white=write("clean_white.png", sim.white),
                capture=write("capture.png", sim.raw.astype(int) + dark),
                white=write("white.png", sim.white.astype(int) + dark), dark=write("dark.png", dark),
                other_dark=write("other_dark.png", dark + 1), small_dark=write("small.png", dark[:200, :300]))


def _views(capture, white, dark=None, calib=None):
    setup = prepare_decoding(CAM, white=white, grid=calib, dark=dark, captures=[capture], cache=True)
    lf = setup.decode(capture)
    return lf.views[..., 0], lf


def test_dark_subtraction_removes_the_pedestal_and_dark_views_stay_dark(files):
    clean, _ = _views(files["clean"], files["clean_white"])
    raised, _ = _views(files["capture"], files["white"])
    fixed, lf = _views(files["capture"], files["white"], files["dark"])
    nx = clean.shape[3]
    black = (slice(None), slice(None), slice(None), slice(int(0.8 * nx), None))   # lenses that see black
    lit = (slice(None), slice(None), slice(None), slice(None, int(0.3 * nx)))
    worst = lambda views: float(views[black].mean(axis=(2, 3)).max() / views[lit].mean(axis=(2, 3)).max())  # noqa
    assert worst(clean) < 0.01
    assert worst(raised) > 0.1               # without the dark frame the pedestal lights the black region
    assert worst(fixed) < 0.01               # with it, every view stays dark there
    np.testing.assert_allclose(fixed, clean, atol=2e-3)   # 8-bit rounding of the pedestal only
    mask = lf.view_mask if lf.view_mask is not None else np.ones(clean.shape[:2], bool)
    assert not fixed[~mask].any()


def test_the_grid_records_the_dark_frame_and_calib_reuses_it(files, tmp_path):
    grid = tmp_path / "grid.json"
    proc = run_cli("calibrate", files["white"], "--camera", files["camera"], "--dark", files["dark"], "-o", grid)
    assert proc.returncode == 0, proc.stderr
    dark = json.loads(grid.read_text())["made_from"]["dark"]
    assert dark["path"] == os.path.abspath(files["dark"]) and dark["hash"].startswith("sha256:")
    reused, _ = _views(files["capture"], None, None, str(grid))          # the recorded dark frame (and white)
    given, _ = _views(files["capture"], files["white"], files["dark"])
    np.testing.assert_array_equal(reused, given)
    proc = run_cli("decode", files["capture"], "--camera", files["camera"], "--calib", grid, "--dark",
                   files["other_dark"], "-o", tmp_path / "x.lfp.npz")
    assert_clean_error(proc, files["other_dark"], str(grid), "differs")


def test_a_dark_frame_of_another_size_is_one_line(files, tmp_path):
    proc = run_cli("refocus", files["capture"], "--camera", files["camera"], "--white", files["white"], "--dark",
                   files["small_dark"], "--a", "1", "-o", tmp_path / "out")
    assert_clean_error(proc, files["small_dark"], "300x200", "352x264")
    assert not (tmp_path / "out").exists()


def test_the_batch_fingerprint_includes_the_dark_frame(files, tmp_path):
    from lfproc.batch import Job
    plain = Job(files["capture"], "c", str(tmp_path), "cam", None, files["white"], (1.0,), False)
    with_dark = Job(files["capture"], "c", str(tmp_path), "cam", None, files["white"], (1.0,), False,
                    dark=files["dark"])
    assert plain.fingerprint() != with_dark.fingerprint()
    copy = tmp_path / "dark.png"
    copy.write_bytes(open(files["dark"], "rb").read())
    before = Job(files["capture"], "c", str(tmp_path), "cam", None, files["white"], (1.0,), False, dark=str(copy))
    first = before.fingerprint()
    copy.write_bytes(open(files["other_dark"], "rb").read())                # the dark frame replaced
    os.utime(copy, ns=(1, 1))
    assert before.fingerprint() != first
