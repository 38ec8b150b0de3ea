"""A Python caller's errors name Python arguments, never the commands' flags: the error paths of the API,
the decode pipeline and the checks below them that a test reaches in a second or two each."""

import dataclasses
import re
import shutil
import warnings

import numpy as np
import pytest

import lfproc
from lfproc import geometry
from lfproc.cli import main
from conftest import SAMPLES

SAMPLE = SAMPLES / "sample"
CAMERAS = SAMPLES / "cameras"

#: a flag, a command's metavar, a command or a mark's backtick: none may reach a Python caller
_COMMAND_WORDS = re.compile(r"(?<![\w-])--?[a-z]|\b(WHITE|DARK|DIR|RAW|OUTDIR|CAM\.toml)\b|\blfproc [a-z]+\b|`")


def speaks_python(message: str, *names: str) -> str:
    """``message`` after checking it is one line naming each of ``names`` and no flag; returns it."""
    assert "\n" not in message and not _COMMAND_WORDS.search(message), message
    for name in names:
        assert name in message, (name, message)
    return message


def error_of(call, *names: str) -> str:
    with pytest.raises(lfproc.LfprocError) as info:
        call()
    return speaks_python(str(info.value), *names)


@pytest.fixture(scope="module")
def cam():
    return lfproc.Camera.from_toml(SAMPLE / "camera.toml")


@pytest.fixture(scope="module")
def grids(tmp_path_factory):
    """GRID.json files of the sample's white image, made by ``lfproc calibrate``: one with a dark frame, one
    whose white image then changed, one whose white image and one whose dark frame then went missing."""
    from PIL import Image

    folder = tmp_path_factory.mktemp("grids")
    white = np.asarray(Image.open(SAMPLE / "white.png"))
    for name, level in (("d1.png", 100), ("d2.png", 200), ("gone-dark.png", 100)):
        Image.fromarray(np.full(white.shape, level, np.uint16)).save(folder / name)
    for name in ("changed.png", "gone.png"):
        shutil.copy(SAMPLE / "white.png", folder / name)
    made = {}
    for key, white_name, dark in (("dark", SAMPLE / "white.png", "d1.png"), ("changed", "changed.png", None),
                                  ("gone", "gone.png", None), ("gone-dark", SAMPLE / "white.png", "gone-dark.png")):
        made[key] = folder / f"{key}.json"
        extra = ("--dark", folder / dark) if dark else ()
        # in process (the command's own main): four calibrations without four interpreter starts
        argv = ["calibrate", folder / white_name, "--camera", SAMPLE / "camera.toml", *extra, "-o", made[key]]
        assert main([str(arg) for arg in argv]) == 0
    changed = np.asarray(Image.open(folder / "changed.png")).copy()
    changed[0, 0] += 1
    Image.fromarray(changed).save(folder / "changed.png")
    (folder / "gone.png").unlink()
    (folder / "gone-dark.png").unlink()
    made["d2"] = folder / "d2.png"
    return made


def test_decode_setup_errors_name_python_arguments(cam, grids, tmp_path):
    from lfproc import prepare_decoding

    capture = SAMPLE / "capture.png"
    error_of(lambda: prepare_decoding(cam), "white=", "white_dir=", "grid=")
    error_of(lambda: prepare_decoding(cam, white=str(SAMPLE / "white.png"), white_dir=str(tmp_path)),
             "white=", "white_dir=")
    error_of(lambda: prepare_decoding(cam, white_dir=tmp_path, captures=[capture]), f"white_dir={tmp_path}",
             "white=")
    error_of(lambda: lfproc.read_light_field(capture, cam, white=SAMPLE / "white.png", white_dir=tmp_path),
             "white=", "white_dir=")
    error_of(lambda: lfproc.read_light_field(capture, cam, grid=grids["changed"]), "has changed", "white=")
    error_of(lambda: lfproc.read_light_field(capture, cam, grid=grids["dark"], dark=grids["d2"]),
             f"dark={grids['d2']}")
    error_of(lambda: lfproc.read_light_field(capture, cam, grid=grids["gone-dark"]), "dark=")


def test_a_grid_without_its_white_image_warns_in_python_words(cam, grids):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lfproc.read_light_field(SAMPLE / "capture.png", cam, grid=grids["gone"])
    said = [str(w.message) for w in caught if issubclass(w.category, lfproc.LfprocWarning)]
    assert any("without devignetting" in text for text in said), said
    for text in said:
        speaks_python(text)


def test_input_checks_name_python_arguments(cam, grids):
    white = np.zeros((60, 84), np.float32)
    error_of(lambda: lfproc.calibrate_white(white, cam, dark=white + 1), "look swapped", "white=", "dark=")
    error_of(lambda: lfproc.calibrate_white(SAMPLE / "capture.png", cam), "white=", "white_is_white=True")
    error_of(lambda: lfproc.read_light_field(SAMPLE / "white.png", cam, white=SAMPLE / "white.png",
                                             grid=grids["changed"]), "capture=", "white=")
    error_of(lambda: lfproc.Camera.from_toml(SAMPLE / "no-camera.toml"), "camera=")


def test_aperture_and_range_errors_name_python_arguments(cam):
    views = np.zeros((cam.m_hat, cam.m_hat, 4, 4, 1), np.float32)
    lf = lfproc.LightField.from_views(views, cam)
    widest, narrowest = geometry.aperture_limits(cam)
    error_of(lambda: lfproc.focal_stack(lf, a=[1.0], aperture=widest / 2), f"aperture={widest / 2:g}")
    error_of(lambda: lfproc.focal_stack(lf, a=[1.0], aperture=narrowest * 2), "aperture=")
    error_of(lambda: lfproc.focal_stack(lf, a=[1.0], aperture="f8"), "aperture='f8'", "e.g. aperture=")
    corner = np.zeros((cam.m_hat, cam.m_hat), bool)
    corner[0, 0] = True                               # lit, but outside the narrowest aperture (the centre view)
    unlit = lfproc.LightField.from_views(views, cam, view_mask=corner)
    error_of(lambda: lfproc.with_aperture(unlit, narrowest), "aperture=")
    no_camera = dataclasses.replace(lf, camera=None)
    error_of(lambda: lfproc.with_aperture(no_camera, narrowest), "camera=")
    error_of(lambda: geometry.plan_slices(cam, 100.0, 200.0, view_extent=0), "aperture=")
    error_of(lambda: geometry.triangulate(cam, 1.0, gap=0), "gap=1")
    from lfproc.depth import depth
    error_of(lambda: depth(views), "camera=")


def test_microscope_depth_errors_name_python_arguments():
    scope = lfproc.Camera.from_toml(CAMERAS / "lfm-20x.toml")
    error_of(lambda: geometry.plan_slices(scope, float("inf"), 0.0, what="z_range_um="), "z_range_um=inf:0.0")
    error_of(lambda: geometry.plan_slices(scope, 10.0, 0.0, step=-1.0, what="z_range_um="), "z_range_um=")
    error_of(lambda: geometry.plan_slices(scope, 1e9, -1e9, step=1e-3, what="z_range_um="), "z_range_um=")
    lf = lfproc.LightField.from_views(np.zeros((scope.m_hat, scope.m_hat, 4, 4, 1), np.float32), scope)
    error_of(lambda: lfproc.depth_map(lf, z_range_um=(0.0, float("inf"))), "z_range_um=")
    error_of(lambda: lfproc.depth_map(lf, depth_range_mm=(100.0, 200.0)), "z_range_um=")


def test_lytro_and_service_errors_name_python_arguments(tmp_path):
    from lfproc import batch
    from lfproc.io import check_white_matches, pick_white_image, read_lytro_metadata
    from lfproc.viewer import make_server

    capture = read_lytro_metadata(SAMPLES / "lytro" / "IMG_0001.lfr")
    other = dataclasses.replace(capture, serial="B0000000000", source="other.raw")
    error_of(lambda: check_white_matches(capture, other), "white_dir=", "white=")
    error_of(lambda: pick_white_image(capture, tmp_path / "none"), "white_dir=")
    error_of(lambda: make_server(str(tmp_path), port=70000), "port=70000")

    def locked():
        with batch.lock_outdir(str(tmp_path / "no" / "folder")):
            pass
    error_of(locked, "outdir=")


def _said(call) -> list:
    """The LfprocWarnings of one call (every one recorded, none filtered out by Python's once-per-line rule)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    return [w for w in caught if issubclass(w.category, lfproc.LfprocWarning)]


def test_warnings_point_at_the_callers_line_once_per_call(cam, grids):
    """Issue 37: a warning raised deep inside a call (the grid fit inside read_light_field, the decode setup, the
    slice checks) is attributed to the caller's line, not to lfproc's or pytest's frames, and each text is said
    once per call."""
    from PIL import Image

    white = np.asarray(Image.open(SAMPLE / "white.png")).astype(np.float64)
    noisy = np.clip(white * (1 + 0.12 * np.random.default_rng(0).standard_normal(white.shape)), 0, 65535)
    noisy = noisy.astype(np.uint16)   # a white image whose pitch implies an exit pupil the camera file denies
    lf = lfproc.read_light_field(SAMPLE / "capture.png", cam, white=SAMPLE / "white.png")
    calls = {
        "calibrate_white": lambda: lfproc.calibrate_white(noisy, cam),
        "read_light_field (its grid fit)": lambda: lfproc.read_light_field(SAMPLE / "capture.png", cam, white=noisy),
        "read_light_field (no white image)": lambda: lfproc.read_light_field(SAMPLE / "capture.png", cam,
                                                                              grid=grids["gone"]),
        "focal_stack (thin border band)": lambda: lfproc.focal_stack(lf, a=[0.0, 2.0]),
    }
    for name, call in calls.items():
        said = _said(call)
        assert said, name                                                      # the case still warns
        assert all(w.filename == __file__ for w in said), (name, [(w.filename, w.lineno) for w in said])
        texts = [str(w.message) for w in said]
        assert len(texts) == len(set(texts)), (name, texts)                    # once per call
