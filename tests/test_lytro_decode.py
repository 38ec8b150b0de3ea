"""Lytro input through the whole pipeline: a simulated capture written as a Lytro file decodes to the same
light field as the same capture written as a 16-bit PNG; white images picked and checked by metadata.

The simulator renders digital numbers between the Lytro file's black and white levels (Illum-like:
10-bit, 64..1023, GRBG, 14.3 px hexagonal lenses; F01-like: 12-bit, 168..4095, BGGR, 9.9 px
hexagonal lenses). The PNG holds the very same numbers as uint16 with a camera file giving the same
levels and CFA, so both readers see identical integers: the only expected difference is float32
rounding of (DN − black) / (white − black), at most 1 ulp of values ≤ 1.1 (2.4e-7); it reaches the views
through the same grid and linear interpolation weights that sum to 1, divided by the same white image
(≥ ~0.3 where views are sampled), so 1e-5 bounds any difference by a wide margin and is still four
orders of magnitude below one DN step (1/959).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import lytrogen
from conftest import assert_clean_error, run_cli
from lfproc import Camera, geometry
from lfproc import simulate
from lfproc.errors import LfprocError
from lfproc.io import write_image
from lfproc.cli.lytro_defaults import camera_for_captures
from lfproc.api import prepare_decoding
from lfproc.simulate import Noise, Plane, Scene
from lfproc.camera import MainLens

MODELS = {
    # name: (camera, sensor shape (H, W), bits, endianness)
    "illum": (Camera(0.0014, 0.020, 0.0406, MainLens(77.59, 77.59, f_number=2.11), grid="hexagonal", cfa="GRBG", black_level=64, white_level=1023), (180, 240), 10, "little"),
    "f01": (Camera(0.0014, 0.0139, 0.025, MainLens(6.45, 6.45, f_number=1.91), grid="hexagonal", cfa="BGGR", black_level=168, white_level=4095), (160, 200), 12, "big"),
}


def render(model):
    cam, shape, _, _ = MODELS[model]
    d = geometry.slice_distance_mm(cam, 0.5)
    scene = Scene((Plane(d, Noise(feature_mm=d / 20, seed=4), tint=(1.0, 0.8, 0.5)),), background=0.2)
    return simulate.render(cam, scene, shape, rotation_deg=0.3, pixel_samples=2, aperture_samples=2, seed=2,
                           ideal_views=False)


@pytest.fixture(scope="module", params=sorted(MODELS))
def written(request, tmp_path_factory):
    """One simulated capture and white image, written as Lytro files (both kinds) and as PNGs."""
    model = request.param
    cam, (height, width), bits, order = MODELS[model]
    sim = render(model)
    assert sim.raw.max() <= cam.white_level and sim.white.max() <= cam.white_level
    folder = tmp_path_factory.mktemp(model)
    write_image(folder / "capture.png", sim.raw)
    write_image(folder / "white.png", sim.white)
    (folder / "camera.toml").write_text(cam.to_toml())
    if model == "illum":
        white_doc = lytrogen.illum_document(width, height)
        capture_doc = lytrogen.illum_document(width, height, modulation=False)
        meta, private = lytrogen.frame_metadata_of(capture_doc)
    else:
        meta = lytrogen.f01_metadata(width, height)
        private = {"camera": {"serialNumber": "A123"}}
        white_doc = dict(meta, privateMetadata=private)
    lytrogen.write_container(folder / "capture.LFR", sim.raw, bits, order, meta, private)
    lytrogen.write_raw_pair(folder / "capture_pair.raw", sim.raw, bits, order, capture_doc if model == "illum"
                            else dict(meta, privateMetadata=private), ".json")
    caldata = folder / "caldata"
    caldata.mkdir()
    lytrogen.write_raw_pair(caldata / "MOD_0000.RAW", sim.white, bits, order, white_doc, ".TXT")
    lytrogen.write_container(folder / "white.lfp", sim.white, bits, order, *lytrogen.frame_metadata_of(white_doc))
    return dict(model=model, folder=folder, sim=sim, camera=cam)


def decoded(camera, capture, white=None, white_dir=None):
    setup = prepare_decoding(camera, white=None if white is None else str(white),
                             white_dir=None if white_dir is None else str(white_dir), captures=[str(capture)],
                             cache=True)
    return setup.decode(str(capture)).views


def test_lytro_files_decode_like_the_png(written):
    folder, cam = written["folder"], written["camera"]
    reference = decoded(cam, folder / "capture.png", folder / "white.png")
    assert reference.shape[-1] == 3 and np.isfinite(reference).all() and reference.std() > 0.01
    for capture, white, white_dir in [("capture.LFR", None, "caldata"), ("capture_pair.raw", "white.lfp", None),
                                      ("capture.LFR", "caldata/MOD_0000.RAW", None)]:
        views = decoded(cam, folder / capture, None if white is None else folder / white,
                        None if white_dir is None else folder / white_dir)
        assert views.shape == reference.shape
        np.testing.assert_allclose(views, reference, rtol=0, atol=1e-5, err_msg=f"{capture} with {white or white_dir}")


def test_camera_from_metadata_decodes_too(written):
    """Without a camera file the metadata's camera (same pitches and grid) gives the same light field."""
    folder = written["folder"]
    cam = camera_for_captures(None, [str(folder / "capture.LFR")])
    assert cam.grid == "hexagonal" and cam.m_hat == written["camera"].m_hat
    if math.isinf(cam.main_optics.exit_pupil_distance_mm):
        views = decoded(cam, folder / "capture.LFR", white_dir=folder / "caldata")
    else:
        # the Illum fixture's metadata says 46 mm, but the simulated white is telecentric: calibration says so
        with pytest.warns(UserWarning, match="implies an exit pupil distance of telecentric"):
            views = decoded(cam, folder / "capture.LFR", white_dir=folder / "caldata")
    reference = decoded(written["camera"], folder / "capture.png", folder / "white.png")
    np.testing.assert_allclose(views, reference, rtol=0, atol=1e-5)


def test_white_dir_picks_same_serial_nearest_zoom_then_focus(tmp_path, capsys):
    cam, (height, width), bits, order = MODELS["illum"]
    dn = np.full((height, width), 500, np.uint16)
    capture = lytrogen.write_container(tmp_path / "IMG.lfr", dn, bits, order, *lytrogen.frame_metadata_of(
        lytrogen.illum_document(width, height, zoom_step=-1000, focus_step=-290, modulation=False)))
    caldata = tmp_path / "caldata"
    (caldata / "sub").mkdir(parents=True)
    whites = {  # name: (serial, zoom step, focus step)
        "MOD_0000.RAW": ("B5143909630", -1200, -290),    # far zoom
        "MOD_0001.RAW": ("B5143909630", -1010, -100),    # nearest zoom, far focus
        "sub/MOD_0002.RAW": ("B5143909630", -990, -280),  # as near in zoom, nearer focus: the one
        "MOD_0003.RAW": ("B0000000000", -1000, -290),    # exact steps, another camera
    }
    for name, (serial, zoom, focus) in whites.items():
        lytrogen.write_raw_pair(caldata / name, dn, bits, order,
                                lytrogen.illum_document(width, height, serial=serial, zoom_step=zoom, focus_step=focus))
    lytrogen.write_raw_pair(caldata / "DARK.RAW", dn, bits, order,
                            lytrogen.illum_document(width, height, zoom_step=-1000, focus_step=-290, modulation=False))
    (caldata / "notes.raw").write_bytes(b"junk")     # no metadata: ignored
    from lfproc.io import pick_white_image, read_lytro_metadata
    choice = pick_white_image(read_lytro_metadata(capture), caldata)
    assert choice.path == str(caldata / "sub" / "MOD_0002.RAW")
    assert "zoom step -990 (capture -1000)" in choice.reason and "nearest of 3" in choice.reason
    # another camera's folder: refused, naming both serials
    other = tmp_path / "other"
    other.mkdir()
    lytrogen.write_raw_pair(other / "MOD_0000.RAW", dn, bits, order,
                            lytrogen.illum_document(width, height, serial="B0000000000"))
    with pytest.raises(LfprocError, match="white images of camera.*B0000000000, none of camera B5143909630"):
        pick_white_image(read_lytro_metadata(capture), other)


def test_white_of_another_camera_or_zoom_is_refused_before_any_work(tmp_path):
    cam, (height, width), bits, order = MODELS["illum"]
    dn = np.full((height, width), 500, np.uint16)
    capture = lytrogen.write_container(tmp_path / "IMG.lfr", dn, bits, order, *lytrogen.frame_metadata_of(
        lytrogen.illum_document(width, height, modulation=False)))
    other_camera = lytrogen.write_raw_pair(tmp_path / "cam.RAW", dn, bits, order,
                                           lytrogen.illum_document(width, height, serial="B0000000000"))
    other_zoom = lytrogen.write_raw_pair(tmp_path / "zoom.RAW", dn, bits, order,
                                         lytrogen.illum_document(width, height, focal_length_m=0.030, zoom_step=200))
    cam_file = tmp_path / "cam.toml"
    cam_file.write_text(cam.to_toml())
    for white, fragment in ((other_camera, "white image of camera B0000000000, but"),
                            (other_zoom, "white image taken at another zoom (focal length 30.00 mm")):
        with pytest.raises(LfprocError, match=fragment.replace("(", r"\(")):
            prepare_decoding(cam, white=str(white), captures=[str(capture)], cache=True)
        out = tmp_path / "out.lfp.npz"
        proc = run_cli("decode", capture, "--camera", cam_file, "--white", white, "-o", out)
        assert_clean_error(proc, str(white), fragment)
        assert not out.exists()


def test_a_capture_given_as_white_image_is_warned_about(tmp_path, capsys):
    cam, (height, width), bits, order = MODELS["illum"]
    sim_white = np.full((height, width), 900, np.uint16)
    capture = lytrogen.write_container(tmp_path / "IMG.lfr", sim_white, bits, order, *lytrogen.frame_metadata_of(
        lytrogen.illum_document(width, height)), modulation=False)
    from lfproc import LfprocWarning

    with pytest.raises(LfprocError), pytest.warns(LfprocWarning) as said:   # no lattice in a flat image; warned first
        prepare_decoding(cam, white=str(capture), captures=[str(capture)], cache=True)
    messages = [str(w.message) for w in said if "marks it as a capture" in str(w.message)]
    assert len(messages) == 1 and "marks it as a capture, not a white image" in messages[0] and \
        str(capture) in messages[0]
    assert capsys.readouterr().err == ""    # a library call prints nothing (the commands print the warning)


def test_processed_picture_is_refused_by_decode(tmp_path, paper_camera):
    stack = tmp_path / "IMG_0001-stk.lfp"
    stack.write_bytes(lytrogen.processed_picture_bytes())
    out = tmp_path / "out.lfp.npz"
    proc = run_cli("decode", stack, "--camera", paper_camera, "--calib", _grid(tmp_path), "-o", out)
    assert_clean_error(proc, str(stack), "holds no raw light field")
    assert not out.exists()


def _grid(tmp_path):
    """A grid file for the paper camera (the refusal must come from the capture, not the grid)."""
    from conftest import SAMPLES
    path = tmp_path / "grid.json"
    grid = simulate.default_grid(Camera.from_toml(SAMPLES / "cameras" / "paper-f100.toml"), (100, 100))
    path.write_text(json.dumps(grid.to_json_dict()))
    return path
