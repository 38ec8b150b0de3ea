"""Issue 38: one camera reader. `lfproc.read_camera` reads a camera TOML, napari-LF's metadata.txt and a Lytro
file's camera, every ``camera=`` of the API takes such a path, and a camera file written from metadata leaves m̂
to the measured micro image pitch (the sea urchin's metadata gave m̂ 15 where its white image gives 17)."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest

import lfproc
import lytrogen
from conftest import assert_clean_error, run_cli
from lfproc import Camera, LfprocError, LfprocWarning

#: napari-LF's "calibrate" table of the real sea urchin set (../shared/real/lfm-seaurchin/metadata.txt)
SEAURCHIN = {"pixel_size": 7.4, "ulens_pitch": 125, "ulens_focal_length": 2500, "ulens_focal_distance": 2433,
             "objective_magnification": 20, "objective_na": 0.5, "tubelens_focal_length": 200.0,
             "center_wavelength": 482, "medium_index": 1.33}


@pytest.fixture
def metadata(tmp_path):
    folder = tmp_path / "seaurchin"
    folder.mkdir()
    path = folder / "metadata.txt"
    path.write_text(json.dumps({"calibrate": SEAURCHIN, "rectify": {}}))
    return path


def test_napari_metadata_reads_as_lfproc_camera_writes_it_with_m_hat_left_to_the_measurement(tmp_path, metadata):
    camera = lfproc.read_camera(metadata)
    assert camera.main_optics.wave_depth_of_field() > 0 and camera.source == str(metadata)   # an objective
    assert camera.pixel_pitch_mm == 0.0074 and camera.mla_pitch_mm == 0.125 and camera.mla_focal_length_mm == 2.433
    assert camera.m_hat == 15 and not camera.micro_image_px_given         # 125 / 7.4 = 16.89 px, nominal only
    proc = run_cli("camera", metadata, "-o", tmp_path / "lfm.toml")
    assert proc.returncode == 0, proc.stderr
    text = (tmp_path / "lfm.toml").read_text()
    assert "\nmicro_image_px" not in text               # was "micro_image_px = 15", which fixed m̂ for every decode
    written = Camera.from_toml(tmp_path / "lfm.toml")
    assert written == camera and not written.micro_image_px_given
    assert Camera.from_toml_string(camera.to_toml()) == camera       # the round trip leaves it unstated too


def test_a_stated_m_hat_stays_stated(tmp_path, metadata):
    camera = lfproc.read_camera(metadata)
    stated = Camera.from_toml_string(camera.to_toml().replace("[decode]", "[decode]\nmicro_image_px = 15"))
    assert stated.micro_image_px_given and "micro_image_px = 15" in stated.to_toml()


def test_camera_from_toml_on_metadata_names_the_reader_to_use(metadata, tmp_path):
    with pytest.raises(LfprocError) as caught:
        Camera.from_toml(metadata)
    message = str(caught.value)
    assert message.startswith(f"{metadata}: a JSON file") and "lfproc.read_camera(path)" in message
    assert "\n" not in message and "not valid TOML" not in message
    container = lytrogen.write_container(tmp_path / "IMG.LFR", np.full((6, 8), 500), 10, "little",
                                         *lytrogen.frame_metadata_of(lytrogen.illum_document(8, 6)))
    with pytest.raises(LfprocError, match=r"a Lytro file, not a camera TOML file; read it with lfproc\.read_camera"):
        Camera.from_toml(container)
    other = tmp_path / "other.json"
    other.write_text('{"a": 1}')
    with pytest.raises(LfprocError, match=r"^.*other\.json: a JSON file, but not napari-LF's metadata"):
        lfproc.read_camera(other)


def test_a_lytro_file_reads_with_one_warning_about_its_focus(tmp_path):
    from lfproc.io import lytro_camera, read_lytro_metadata

    path = lytrogen.write_container(tmp_path / "IMG.LFR", np.full((6, 8), 500), 10, "little",
                                    *lytrogen.frame_metadata_of(lytrogen.illum_document(8, 6)))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        camera = lfproc.read_camera(path)
    assert [w.category for w in caught] == [LfprocWarning]
    assert "focused at infinity" in str(caught[0].message) and "focused_at" in str(caught[0].message)
    assert camera == lytro_camera(read_lytro_metadata(str(path))).camera
    assert not camera.micro_image_px_given


def test_every_camera_argument_takes_the_metadata_file(metadata):
    """calibrate_white and read_light_field with camera= napari-LF's metadata: a microscope white rendered through
    lenslets 1.8 % larger than the metadata says (the sea urchin's case) decodes with the measured m̂ 17."""
    from lfproc.simulate import render_microscope_sensor

    true = Camera.from_toml_string(lfproc.read_camera(metadata).to_toml().replace(
        "relay_magnification = 1.0", "relay_magnification = 1.018"))
    white = render_microscope_sensor(true, None, (240, 240), pixel_samples=2, aperture_samples=1)
    grid = lfproc.calibrate_white(0.05 + 0.9 * white, metadata, white_is_white=True)
    assert grid.pitch_px == pytest.approx(true.pitch_px, abs=0.02)           # 17.196 px
    lf = lfproc.read_light_field(0.05 + 0.9 * white * 0.8, metadata, white=0.05 + 0.9 * white, grid=grid)
    assert lf.camera.m_hat == 17 and lf.views.shape[:2] == (17, 17)
    assert lf.inputs["camera"] == str(metadata)              # the file the camera came from, in the provenance


def test_read_camera_is_lazy():
    code = "import sys, lfproc; lfproc.read_camera; print('OpenImageIO' in sys.modules, 'rawpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_the_command_line_names_the_reader_for_a_metadata_file_given_as_camera(metadata, tmp_path):
    proc = run_cli("geometry", "--camera", metadata)
    assert_clean_error(proc, str(metadata), "not a camera TOML file", "lfproc camera")
