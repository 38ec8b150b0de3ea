"""Lytro files and napari-LF metadata from real instruments (``../shared/real``; skipped where absent).

* ``lytro/illum-picture-toc.json``: a real Illum picture's table of contents; the picture is written here
  byte for byte around it (real metadata, small synthetic JPEGs and depth map: the real images are not
  available);
* ``lytro/f01-IMG_0001-stk.lfp``: a real first-generation refocus stack (no camera metadata inside);
* ``lytro/f01-exiftool-stripped.lfp``: a real first-generation container, its image section removed, and
  ExifTool's independent reading of it (``.exiftool-tags.txt``);
* ``lfm-seaurchin/metadata.txt``: napari-LF's settings of a real light-field microscope.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

import lytropics
from lytropics import cli, illum_thin_lens, info_of


def exiftool_tags(path) -> dict:
    """ExifTool's ``-G -D``-style listing as {TagName: printed value} (first occurrence of each tag)."""
    tags = {}
    for line in path.read_text().splitlines():
        match = re.match(r"\[[^\]]*\] (\S+) - [^:]*: (.*)$", line)
        if match:
            tags.setdefault(match.group(1), match.group(2).strip())
    return tags


def newton_distance(lam, *, f_u, n, p_m, f_s, b_u):
    x_image = b_u - f_u - lam * n * p_m
    return math.inf if x_image <= 0 else f_s + b_u + f_u + f_u ** 2 / x_image


# ----------------------------------------------------------------------------- Illum picture schema

@pytest.fixture
def illum(real_dir, tmp_path):
    toc = json.loads((real_dir / "lytro" / "illum-picture-toc.json").read_text())
    data, written = lytropics.illum_picture_from_toc(toc)
    return lytropics.write(tmp_path / "IMG_0480.LFP", data), written


def test_real_illum_picture_camera(illum, tmp_path, capsys):
    from lfproc import Camera

    path, _ = illum
    info = info_of(capsys, path)
    assert info["camera_model"] == "ILLUM" and info["serial"] == "45142500380" and info["camera_known"] is True
    assert (info["raw_frame_width"], info["raw_frame_height"], info["cfa"]) == (7728, 5368, "GRBG")
    status, text, _ = cli(capsys, "info", path)
    assert "camera_model           ILLUM" in text and "lacks" not in text
    status, _, err = cli(capsys, "camera", path, "-o", tmp_path / "illum.toml")
    assert status == 0, err
    cam = Camera.from_toml(tmp_path / "illum.toml")
    assert round(cam.main_optics.focal_length_mm, 3) == 13.886 and round(cam.main_optics.f_number, 3) == 2.082
    assert (cam.pixel_pitch_mm, cam.mla_pitch_mm, cam.mla_focal_length_mm) == (0.0014, 0.02, 0.037)
    assert cam.grid == "hexagonal" and cam.telecentric            # exitPupilOffset.z 10000 m
    text = (tmp_path / "illum.toml").read_text()
    assert "focusStep = 814" in text and "infinityLambda = 15.40946" in text


def test_real_illum_picture_exports_in_mm(illum, tmp_path, capsys):
    import tifffile

    path, toc = illum
    lens = illum_thin_lens(toc)
    f_u, n, p_m, f_s, b_u = (lens[k] for k in ("f_u", "n", "p_m", "f_s", "b_u"))
    status, _, err = cli(capsys, "export", path, "-o", tmp_path / "out")
    assert status == 0, err
    focus = [entry["focus"] for entry in toc["views"][0]["accelerations"][0]["perImage"]]
    assert len(focus) == 10
    for k, lam in enumerate(focus):
        sidecar = json.loads((tmp_path / "out" / f"IMG_0480_stack_{k:02d}.json").read_text())
        assert sidecar["lambda"] == lam
        assert sidecar["distance_mm"] == pytest.approx(newton_distance(lam, f_u=f_u, n=n, p_m=p_m, f_s=f_s, b_u=b_u),
                                                       rel=1e-9)
        assert sidecar["near_mm"] < sidecar["distance_mm"] < sidecar["far_mm"] and sidecar["dof_mm"] > 0
    depth = tifffile.imread(tmp_path / "out" / "IMG_0480_depth.tif")
    lam = tifffile.imread(tmp_path / "out" / "IMG_0480_depth_lambda.tif")
    assert depth.shape == lam.shape == (60, 88)
    assert json.loads((tmp_path / "out" / "IMG_0480_depth.json").read_text())["unit"] == "mm"
    assert np.all(np.diff(depth[np.isfinite(depth)].ravel()) >= 0)        # a ramp in lambda: farther and farther


# ----------------------------------------------------------------------------- first generation

def test_real_first_generation_stack(real_dir, tmp_path, capsys):
    stk = real_dir / "lytro" / "f01-IMG_0001-stk.lfp"
    info = info_of(capsys, stk)
    lambdas = [i["lambda"] for i in info["focus_stack"]["images"]]
    assert len(lambdas) == 12 and lambdas[0] == pytest.approx(-8.922927856445312)
    assert info["picture"] == ["focus stack", "depth lookup table"] and info["damaged"] is False
    assert info["camera_known"] is False and info["raw_frame"].startswith("referenced, not contained")
    status, _, err = cli(capsys, "export", stk, "-o", tmp_path / "plain")
    assert status == 0, err
    assert (tmp_path / "plain" / "f01-IMG_0001-stk_depth_lambda_preview.png").exists()
    assert not (tmp_path / "plain" / "f01-IMG_0001-stk_depth.tif").exists()
    exported = tmp_path / "plain" / "f01-IMG_0001-stk_stack_00.jpg"
    assert info_of(capsys, exported)["raw_light_field"] is False
    # the camera from the other real first-generation file (same camera model, its own zoom)
    other = real_dir / "lytro" / "f01-exiftool-stripped.lfp"
    status, _, err = cli(capsys, "camera", other, "-o", tmp_path / "f01.toml")
    assert status == 0, err
    status, _, err = cli(capsys, "export", stk, "--camera", tmp_path / "f01.toml", "-o", tmp_path / "mm")
    assert status == 0, err
    from lfproc import Camera
    cam = Camera.from_toml(tmp_path / "f01.toml")
    for k, lam in enumerate(lambdas):
        sidecar = json.loads((tmp_path / "mm" / f"f01-IMG_0001-stk_stack_{k:02d}.json").read_text())
        expected = newton_distance(lam, f_u=cam.main_optics.focal_length_mm, n=cam.main_optics.f_number, p_m=cam.mla_pitch_mm,
                                   f_s=cam.mla_focal_length_mm, b_u=cam.main_optics.image_distance_mm)
        assert (sidecar["distance_mm"] is None) == math.isinf(expected)
        if math.isfinite(expected):
            assert sidecar["distance_mm"] == pytest.approx(expected, rel=1e-9)
    status, _, err = cli(capsys, "viewer", stk, "-o", tmp_path / "v")
    assert status == 0, err


def test_real_first_generation_metadata_matches_exiftool(real_dir, tmp_path, capsys):
    """Every field lfproc reads, against ExifTool's independent reading of the same container."""
    path = real_dir / "lytro" / "f01-exiftool-stripped.lfp"
    tags = exiftool_tags(real_dir / "lytro" / "f01-exiftool-stripped.exiftool-tags.txt")
    info = info_of(capsys, path)
    assert info["raw_light_field"] is False and info["raw_frame"].startswith("missing")
    assert info["serial"] == tags["CameraSerialNumber"] == "A202110453"
    assert info["camera_model"] == tags["CameraModel"] == "F01"
    assert (info["width"], info["height"]) == (int(tags["ImageWidth"]), int(tags["ImageHeight"])) == (3280, 3280)
    assert info["bits_per_pixel"] == int(tags["ImageRawDetailsPixelPackingBitsPerPixel"]) == 12
    assert info["endianness"] == tags["ImageRawDetailsPixelPackingEndianness"] == "big"
    assert tags["ImageRawDetailsMosaicUpperLeftPixel"] == "b" and info["cfa"] == "BGGR"    # b at (0, 0)
    for channel in ("R", "Gr", "Gb", "B"):
        assert float(tags[f"ImageRawDetailsPixelFormatBlack{channel}"]) == 168
        assert float(tags[f"ImageRawDetailsPixelFormatWhite{channel}"]) == 4095
    assert info["black_level"] == [[168, 168], [168, 168]] and info["white_level"] == [[4095, 4095], [4095, 4095]]
    lens, mla = info["lens"], info["mla"]
    assert abs(lens["focal_length_mm"] - float(tags["DevicesLensFocalLength"].split()[0])) <= 0.05 + 1e-9   # "6.4 mm"
    assert lens["focal_length_mm"] == pytest.approx(6.45, abs=1e-6)
    assert round(lens["f_number"], 1) == float(tags["DevicesLensFNumber"])
    assert lens["zoom_step"] == int(tags["DevicesLensZoomStep"]) == 981
    assert lens["focus_step"] == int(tags["DevicesLensFocusStep"]) == 721
    assert lens["infinity_lambda"] == pytest.approx(float(tags["DevicesLensInfinityLambda"]), rel=1e-12)
    assert lens["exit_pupil_distance_mm"] == pytest.approx(float(tags["DevicesLensExitPupilOffsetZ"]) * 1e3, rel=1e-12)
    # ExifTool prints the pixel pitch as a focal-plane resolution in pixels per inch
    assert info["sensor"]["pixel_pitch_mm"] == pytest.approx(25.4 / float(tags["DevicesSensorPixelPitch"]), rel=1e-9)
    assert info["sensor"]["pixel_pitch_mm"] == pytest.approx(0.0014, rel=1e-7)
    assert mla["pitch_mm"] == pytest.approx(float(tags["DevicesMlaLensPitch"]) * 1e3, rel=1e-12)
    assert round(mla["pitch_mm"] * 1e3, 4) == 13.8986                          # um, as the README states it
    assert mla["tiling"] == tags["DevicesMlaTiling"]
    assert math.radians(mla["rotation_deg"]) == pytest.approx(float(tags["DevicesMlaRotation"]), rel=1e-12)
    assert mla["sensor_offset_mm"][2] == pytest.approx(float(tags["DevicesMlaSensorOffsetZ"]) * 1e3, rel=1e-12)
    status, _, err = cli(capsys, "camera", path, "-o", tmp_path / "f01.toml")
    assert status == 0, err


# ----------------------------------------------------------------------------- napari-LF metadata

def test_real_napari_metadata(real_dir, tmp_path, capsys):
    from lfproc import Camera

    status, _, err = cli(capsys, "camera", real_dir / "lfm-seaurchin" / "metadata.txt", "-o", tmp_path / "lfm.toml")
    assert status == 0, err
    cam = Camera.from_toml(tmp_path / "lfm.toml")
    scope = cam.main_optics
    assert (cam.pixel_pitch_mm, cam.mla_pitch_mm, cam.mla_focal_length_mm) == (0.0074, 0.125, 2.433)
    assert (scope.objective_magnification, scope.numerical_aperture, scope.immersion_index) == (20, 0.5, 1.33)
    assert (scope.tube_lens_focal_length_mm, scope.wavelength_nm, scope.relay_magnification) == (200, 482, 1)
    assert cam.m_hat == 15 and cam.name == "lfm-seaurchin (napari-LF)"
    assert "ulens_focal_length = 2500 um" in (tmp_path / "lfm.toml").read_text()
