"""Tests of lfproc.io: reading captures (LibRaw and OpenImageIO), writing images with metadata,
GIFs and sidecars. Every file is small and written by the test itself."""

from __future__ import annotations

import json
import math
import os
import struct
import tempfile
import zlib

import numpy as np
import OpenImageIO as oiio
import pytest
import tifffile
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from PIL import Image

from lfproc import io as lio
from lfproc.camera import Camera, MainLens
from lfproc.errors import LfprocError

# DNG CFAPattern codes: 0 = red, 1 = green, 2 = blue
BAYER_CODES = {"RGGB": (0, 1, 1, 2), "BGGR": (2, 1, 1, 0), "GRBG": (1, 0, 2, 1), "GBRG": (1, 2, 0, 1)}
XTRANS_CODES = (1, 1, 0, 1, 1, 2, 1, 1, 2, 1, 1, 0, 2, 0, 1, 0, 2, 1,
                1, 1, 2, 1, 1, 0, 1, 1, 0, 1, 1, 2, 0, 2, 1, 2, 0, 1)


def write_dng(path, mosaic, cfa_codes=BAYER_CODES["RGGB"], black=(64,), white=4095, repeat=(2, 2),
              active_area=None):
    """A minimal uncompressed CFA DNG (the DNG 1.4 tags LibRaw needs), written with tifffile.

    ``black`` is one level for all pixels or four levels for the 2×2 positions (BlackLevelRepeatDim).
    """
    black_dim = (1, 1) if len(black) == 1 else (2, 2)
    tags = [
        (50706, "B", 4, (1, 4, 0, 0), True),              # DNGVersion
        (50708, "s", 0, "lfproc test camera", True),      # UniqueCameraModel
        (33421, "H", 2, repeat, True),                    # CFARepeatPatternDim
        (33422, "B", len(cfa_codes), cfa_codes, True),    # CFAPattern
        (50710, "B", 3, (0, 1, 2), True),                 # CFAPlaneColor
        (50713, "H", 2, black_dim, True),                 # BlackLevelRepeatDim
        (50714, "H", len(black), tuple(black), True),     # BlackLevel
        (50717, "H", 1, white, True),                     # WhiteLevel
        (50721, "2i", 9, (1, 1, 0, 1, 0, 1, 0, 1, 1, 1, 0, 1, 0, 1, 0, 1, 1, 1), True),  # ColorMatrix1 = I
    ]
    if active_area is not None:
        tags.append((50829, "I", 4, tuple(active_area), True))  # ActiveArea top, left, bottom, right
    tifffile.imwrite(path, np.asarray(mosaic, np.uint16), photometric="CFA", subfiletype=0, extratags=tags)


def make_camera(**levels):
    return Camera(0.01, 0.25, 2.749, MainLens(99.5, 100.0), **levels)


def oiio_write(path, pixels, type_name):
    """Write pixels with OpenImageIO directly (independent of lfproc's writer)."""
    pixels = pixels[:, :, None] if pixels.ndim == 2 else pixels
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], type_name)
    spec.attribute("oiio:UnassociatedAlpha", 1)      # store colour channels as given (no un-premultiplying)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), out.geterror()
    assert out.write_image(pixels), out.geterror()
    out.close()


def oiio_read_native(path, unassociated=False):
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", int(unassociated))
    inp = oiio.ImageInput.open(str(path), config)
    spec = inp.spec()
    pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.UNKNOWN)
    attributes = {a.name: a.value for a in spec.extra_attribs}
    inp.close()
    return pixels, attributes


def srgb_reference(x):
    """IEC 61966-2-1 encoding, written out per value."""
    x = min(max(float(x), 0.0), 1.0)
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


def folder_is_empty(folder):
    return os.listdir(folder) == []


# ===================================================================== LibRaw captures

@pytest.mark.parametrize("pattern", sorted(BAYER_CODES))
def test_dng_levels_and_cfa_per_position(tmp_path, pattern):
    rng = np.random.default_rng(1)
    mosaic = rng.integers(0, 4096, size=(32, 48)).astype(np.uint16)    # LibRaw wants >= 22 px a side
    mosaic[0, :4] = (5, 4095, 4095, 4200)            # below black, at white, above white: not clipped
    tile_black = np.array([[10, 20], [30, 40]], float)
    path = tmp_path / "capture.dng"
    write_dng(path, mosaic, BAYER_CODES[pattern], black=(10, 20, 30, 40), white=4095)
    # the camera's levels and CFA must be ignored for LibRaw raws
    capture = lio.read_capture(path, camera=make_camera(black_level=1000, white_level=2000))
    black = np.tile(tile_black, (16, 24))
    expected = (mosaic - black) / (4095 - black)
    assert capture.cfa == pattern and capture.is_mosaic
    assert capture.data.dtype == np.float32 and capture.data.shape == (32, 48)
    np.testing.assert_allclose(capture.data, expected, rtol=1e-6, atol=1e-7)
    assert capture.data[0, 0] < 0 and capture.data[0, 3] > 1
    assert capture.data[0, 1] == pytest.approx(1.0)    # (4095 - 20) / (4095 - 20)
    assert capture.source == str(path)


def test_dng_uses_only_the_visible_area(tmp_path):
    mosaic = (np.arange(24 * 36).reshape(24, 36) % 3000 + 100).astype(np.uint16)
    path = tmp_path / "area.dng"
    write_dng(path, mosaic, BAYER_CODES["GRBG"], black=(100,), white=4000, active_area=(2, 4, 24, 36))
    capture = lio.read_capture(path)
    np.testing.assert_allclose(capture.data, (mosaic[2:, 4:] - 100.0) / 3900.0, rtol=1e-6)
    assert capture.cfa == "GRBG"


def test_dng_that_libraw_rejects_is_an_error_not_a_plain_tiff(tmp_path):
    path = tmp_path / "tiny.dng"           # LibRaw refuses sensors under 22 px a side
    write_dng(path, np.full((16, 16), 1000))
    with pytest.raises(LfprocError, match="not a readable image or camera raw") as info:
        lio.read_capture(path)
    assert str(path) in str(info.value)


def test_dng_with_black_above_white_is_refused(tmp_path):
    path = tmp_path / "levels.dng"
    write_dng(path, np.full((32, 32), 1000), black=(5000,), white=4095)
    with pytest.raises(LfprocError, match="white level 4095 is not above its black level 5000"):
        lio.read_capture(path)


def test_xtrans_dng_is_refused(tmp_path):
    path = tmp_path / "xtrans.dng"
    write_dng(path, np.full((24, 36), 1000), XTRANS_CODES, repeat=(6, 6))
    with pytest.raises(LfprocError, match="unsupported colour filter array") as info:
        lio.read_capture(path)
    assert str(path) in str(info.value)


def test_bayer_pattern_from_colors():
    rgbg = np.array([[0, 1], [3, 2]])
    assert lio.bayer_pattern_from_colors(np.tile(rgbg, (3, 3)), "RGBG") == "RGGB"
    assert lio.bayer_pattern_from_colors(np.array([[2, 1], [1, 0]]), "RGB") == "BGGR"
    assert lio.bayer_pattern_from_colors(np.zeros((4, 4), int), "G", num_colors=1) == "none"
    with pytest.raises(LfprocError, match="X-Trans"):
        lio.bayer_pattern_from_colors(np.array(XTRANS_CODES).reshape(6, 6), "RGBG")
    with pytest.raises(LfprocError, match="Bayer"):
        lio.bayer_pattern_from_colors(np.array([[0, 1], [2, 3]]), "CMYG")   # CMYG is not Bayer
    with pytest.raises(LfprocError):
        lio.bayer_pattern_from_colors(np.array([[0, 1]]), "RGBG")


# ===================================================================== OpenImageIO captures

def test_png8_mono_uses_camera_levels_and_cfa(tmp_path):
    dn = np.array([[0, 16, 100], [200, 255, 128]], np.uint8)
    path = tmp_path / "cap8.png"
    oiio_write(path, dn, "uint8")
    capture = lio.read_capture(path, camera=make_camera(cfa="BGGR", black_level=16, white_level=240))
    assert capture.cfa == "BGGR" and capture.data.shape == (2, 3)
    np.testing.assert_allclose(capture.data, (dn - 16.0) / 224.0, rtol=1e-6)
    without_camera = lio.read_capture(path)
    assert without_camera.cfa == "none"
    np.testing.assert_allclose(without_camera.data, dn / 255.0, rtol=1e-6)


@pytest.mark.parametrize("name", ["cap16.png", "cap16.tif"])
def test_16bit_mono_levels(tmp_path, name):
    dn = np.array([[0, 512, 4095], [60000, 65535, 1000]], np.uint16)
    path = tmp_path / name
    oiio_write(path, dn, "uint16")
    capture = lio.read_capture(path, camera=make_camera(cfa="GBRG", black_level=512, white_level=4095))
    assert capture.cfa == "GBRG"
    np.testing.assert_allclose(capture.data, (dn - 512.0) / 3583.0, rtol=1e-6)   # not clipped
    np.testing.assert_allclose(lio.read_capture(path).data, dn / 65535.0, rtol=1e-6)


def test_rgba_png_drops_alpha_and_applies_levels(tmp_path):
    rgba = np.random.default_rng(2).integers(0, 65536, size=(5, 4, 4)).astype(np.uint16)
    path = tmp_path / "rgba.png"
    oiio_write(path, rgba, "uint16")
    capture = lio.read_capture(path, camera=make_camera(cfa="RGGB", black_level=100, white_level=60000))
    assert capture.data.shape == (5, 4, 3) and capture.cfa == "none"   # colour files are not mosaics
    np.testing.assert_allclose(capture.data, (rgba[:, :, :3] - 100.0) / 59900.0, rtol=1e-6)


@pytest.mark.parametrize("name,type_name", [("f.tif", "float"), ("f.exr", "float"), ("h.exr", "half")])
def test_float_files_are_linear_as_stored(tmp_path, name, type_name):
    values = np.array([[-0.25, 0.0, 0.5], [1.0, 2.5, 0.125]], np.float32)   # exact in half too
    path = tmp_path / name
    oiio_write(path, values, type_name)
    capture = lio.read_capture(path, camera=make_camera(cfa="RGGB", black_level=100, white_level=200))
    assert capture.cfa == "RGGB"
    np.testing.assert_array_equal(capture.data, values)      # camera levels ignored for float data


def test_float_file_with_nan_is_refused(tmp_path):
    path = tmp_path / "nan.tif"
    oiio_write(path, np.array([[0.0, np.nan], [np.inf, 1.0]], np.float32), "float")
    for reader in (lio.read_capture, lio.read_image):
        with pytest.raises(LfprocError, match="NaN") as info:
            reader(path)
        assert str(path) in str(info.value)


def test_white_level_above_8bit_range_is_refused(tmp_path):
    path = tmp_path / "cap8.png"
    oiio_write(path, np.zeros((2, 2), np.uint8), "uint8")
    with pytest.raises(LfprocError, match="white_level"):
        lio.read_capture(path, camera=make_camera(white_level=65535))   # given explicitly and > 255


def test_levels_default_to_the_files_own_range(tmp_path):
    """Issue 14: a camera file without levels reads an 8-bit PNG against 255 and a 16-bit one against 65535."""
    for dtype, top in ((np.uint8, 255), (np.uint16, 65535)):
        path = tmp_path / f"cap{top}.png"
        pixels = np.array([[0, top // 5], [top // 2, top]], dtype)
        oiio_write(path, pixels, "uint8" if top == 255 else "uint16")
        capture = lio.read_capture(path, camera=make_camera())
        np.testing.assert_allclose(capture.data, pixels.astype(np.float64) / top, atol=1e-6)


def test_black_level_at_or_above_the_files_white_is_refused(tmp_path):
    """Issue 14: a level given explicitly and contradicted by the file is an error, not a division by <= 0."""
    path = tmp_path / "cap8.png"
    oiio_write(path, np.full((2, 2), 7, np.uint8), "uint8")
    for camera in (make_camera(black_level=255), make_camera(black_level=300)):     # white defaults to 255
        with pytest.raises(LfprocError, match="black_level .* is not below this file's white level 255") as info:
            lio.read_capture(path, camera=camera)
        assert str(path) in str(info.value)
    assert lio.read_capture(path, camera=make_camera(black_level=254)).data[0, 0] == pytest.approx(-247.0)


def test_read_image_is_as_stored(tmp_path):
    rgba = np.array([[[0, 255, 51, 102]]], np.uint8)
    oiio_write(tmp_path / "a.png", rgba, "uint8")
    image = lio.read_image(tmp_path / "a.png")
    assert image.dtype == np.float32 and image.shape == (1, 1, 4)
    np.testing.assert_allclose(image, rgba / 255.0, rtol=1e-6)
    oiio_write(tmp_path / "m.exr", np.array([[3.5, -1.0]], np.float32), "float")
    np.testing.assert_array_equal(lio.read_image(tmp_path / "m.exr"), [[[3.5], [-1.0]]])


def test_tiff_with_a_raw_extension_falls_back_to_openimageio(tmp_path):
    # LibRaw does not recognise a plain TIFF, so the reader falls back to OpenImageIO
    dn = np.array([[10, 20], [30, 40]], np.uint16)
    path = tmp_path / "actually_tiff.cr2"
    oiio_write(tmp_path / "plain.tif", dn, "uint16")
    os.replace(tmp_path / "plain.tif", path)
    capture = lio.read_capture(path)
    np.testing.assert_allclose(capture.data, dn / 65535.0, rtol=1e-6)


# ===================================================================== unreadable inputs

def _truncate(path, keep_fraction):
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep_fraction)])


def _bad_files(tmp_path):
    files = {}
    files["missing"] = tmp_path / "missing.png"
    files["empty"] = tmp_path / "empty.exr"
    files["empty"].write_bytes(b"")
    files["junk_png"] = tmp_path / "junk.png"
    files["junk_png"].write_bytes(b"this is not an image" * 20)
    files["junk_raw"] = tmp_path / "junk.nef"
    files["junk_raw"].write_bytes(b"\x00\x01garbage" * 50)
    files["unknown_ext"] = tmp_path / "notes.xyz"
    files["unknown_ext"].write_text("hello" * 40)
    files["directory"] = tmp_path / "folder.png"
    files["directory"].mkdir()
    big = np.random.default_rng(3).integers(0, 65536, size=(64, 64)).astype(np.uint16)
    for name, fraction in (("trunc.png", 0.5), ("trunc.tif", 0.6), ("trunc.exr", 0.5)):
        path = tmp_path / name
        oiio_write(path, big if name != "trunc.exr" else big.astype(np.float32), "uint16" if name != "trunc.exr"
                   else "float")
        _truncate(path, fraction)
        files[name] = path
    for name, fraction in (("head.dng", 0.02), ("tail.dng", 0.9)):
        path = tmp_path / name
        write_dng(path, big % 4096)
        _truncate(path, fraction)
        files[name] = path
    zero = tmp_path / "zero.png"          # a PNG whose header says width 0
    oiio_write(zero, np.zeros((2, 2), np.uint8), "uint8")
    data = bytearray(zero.read_bytes())
    data[16:20] = struct.pack(">I", 0)
    data[29:33] = struct.pack(">I", zlib.crc32(bytes(data[12:29])))   # a valid CRC: libpng sees width 0
    zero.write_bytes(bytes(data))
    files["zero_size"] = zero
    return files


def test_bad_inputs_raise_one_line_errors_naming_the_file(tmp_path):
    for label, path in _bad_files(tmp_path).items():
        for reader in (lio.read_capture, lio.read_image):
            with pytest.raises(LfprocError) as info:
                reader(path)
            message = str(info.value)
            assert str(path) in message and "\n" not in message, (label, message)
    with pytest.raises(LfprocError, match="empty"):
        lio.read_capture(tmp_path / "empty.exr")
    with pytest.raises(LfprocError, match="not found"):
        lio.read_capture(tmp_path / "missing.png")
    with pytest.raises(LfprocError, match="truncated or corrupt"):
        lio.read_capture(tmp_path / "tail.dng")


# ===================================================================== writing images

def _metadata():
    return {"source": "capture.dng", "a": 1.5, "distance_mm": 313.0661, "near_mm": 301.5, "far_mm": math.inf,
            "dof_mm": None, "slice": np.int64(3), "view": [1, 2]}


def _strict_loads(text):
    def refuse(constant):
        raise AssertionError(f"non-strict JSON constant {constant}")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("name", ["out.tif", "out.tiff", "out.png", "out.exr", "out.jpg"])
def test_metadata_round_trip(tmp_path, name):
    path = tmp_path / name
    lio.write_image(path, np.full((4, 5, 3), 0.25, np.float32), metadata=_metadata())
    expected = {"source": "capture.dng", "a": 1.5, "distance_mm": 313.0661, "near_mm": 301.5, "far_mm": None,
                "dof_mm": None, "slice": 3, "view": [1, 2]}
    assert lio.read_metadata(path) == expected
    _, attributes = oiio_read_native(path)
    assert _strict_loads(attributes["ImageDescription"]) == expected
    if name.endswith(".exr"):      # typed attributes survive in the EXR header
        assert attributes["lfproc:a"] == 1.5 and attributes["lfproc:slice"] == 3
        assert attributes["lfproc:far_mm"] == "inf" and attributes["lfproc:source"] == "capture.dng"
        assert "lfproc:dof_mm" not in attributes and "lfproc:view" not in attributes
    if name.endswith(".png"):      # PNG text chunks keep strings only, so numbers are written as text
        assert attributes["lfproc:distance_mm"] == "313.0661" and attributes["lfproc:far_mm"] == "inf"
        assert attributes["lfproc:slice"] == "3"


def test_read_metadata_without_lfproc_metadata_is_empty(tmp_path):
    oiio_write(tmp_path / "plain.png", np.zeros((2, 2), np.uint8), "uint8")
    assert lio.read_metadata(tmp_path / "plain.png") == {}
    lio.write_image(tmp_path / "none.tif", np.zeros((2, 2), np.float32))
    assert lio.read_metadata(tmp_path / "none.tif") == {}
    with pytest.raises(LfprocError, match="not found"):
        lio.read_metadata(tmp_path / "missing.tif")


@pytest.mark.parametrize("name", ["float.tif", "float.exr"])
def test_float_formats_are_exact(tmp_path, name):
    image = np.random.default_rng(4).normal(size=(6, 7, 3)).astype(np.float32)
    lio.write_image(tmp_path / name, image)
    pixels, _ = oiio_read_native(tmp_path / name)
    assert pixels.dtype == np.float32
    np.testing.assert_array_equal(pixels, image)
    mono = image[:, :, 0]
    lio.write_image(tmp_path / name, mono)                # (H, W) becomes one channel
    np.testing.assert_array_equal(lio.read_image(tmp_path / name), mono[:, :, None])


def test_png16_is_clipped_rounded_and_linear(tmp_path):
    image = np.array([[-0.5, 0.0, 0.5], [1.0, 7.0, 1.0 / 65535 * 2.4]], np.float32)
    path = tmp_path / "lin.png"
    lio.write_image(path, image)
    pixels, attributes = oiio_read_native(path)
    assert pixels.dtype == np.uint16
    np.testing.assert_array_equal(pixels[:, :, 0], [[0, 0, 32768], [65535, 65535, 2]])
    # a gAMA chunk of exactly 1.0 (100000) tells viewers the data is linear
    data = path.read_bytes()
    at = data.index(b"gAMA")
    assert struct.unpack(">I", data[at + 4:at + 8])[0] == 100000
    assert b"sRGB" not in data
    rgba = np.array([[[0.2, 0.4, 0.1, 0.5]]], np.float32)      # colour is stored as given, not divided by alpha
    lio.write_image(path, rgba)
    pixels, _ = oiio_read_native(path, unassociated=True)
    np.testing.assert_array_equal(pixels, np.round(rgba * 65535))


@settings(max_examples=15, deadline=None)
@given(hnp.arrays(np.float32, hnp.array_shapes(min_dims=3, max_dims=3, min_side=1, max_side=6)
                  .filter(lambda s: s[2] in (1, 3, 4)),
                  elements=st.floats(-0.5, 1.5, width=32)))
def test_png16_round_trip_property(image):
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "p.png")
        lio.write_image(path, image)
        back = lio.read_image(path)
    assert back.shape == image.shape
    assert np.max(np.abs(back - np.clip(image, 0, 1))) <= 0.5 / 65535 + 1e-7


def test_jpeg_is_srgb_encoded(tmp_path):
    levels = [0.0, 0.001, 0.0031308, 0.18, 0.5, 1.0]
    image = np.zeros((48, 8 * len(levels), 1), np.float32)
    for i, level in enumerate(levels):
        image[:, 8 * i:8 * (i + 1)] = level        # flat 8×8-aligned blocks: JPEG keeps them within ±1
    path = tmp_path / "view.jpg"
    lio.write_image(path, image)
    pixels, attributes = oiio_read_native(path)
    assert pixels.dtype == np.uint8
    for i, level in enumerate(levels):
        assert abs(int(pixels[20, 8 * i + 4, 0]) - round(255 * srgb_reference(level))) <= 1
    assert round(255 * srgb_reference(0.18)) == 118           # the familiar 18 % grey
    np.testing.assert_allclose(lio.srgb_encode(np.array(levels)), [srgb_reference(v) for v in levels], atol=1e-6)


@pytest.mark.parametrize("name", ["raw.png", "raw.tif"])
def test_uint16_sensor_data_is_written_exactly(tmp_path, name):
    data = np.random.default_rng(5).integers(0, 65536, size=(9, 11)).astype(np.uint16)
    data[0, :3] = (0, 1, 65535)
    path = tmp_path / name
    lio.write_image(path, data, metadata={"kind": "simulated"}, format="uint16")
    pixels, _ = oiio_read_native(path)
    assert pixels.dtype == np.uint16
    np.testing.assert_array_equal(pixels[:, :, 0], data)
    lio.write_image(path, data)                               # uint16 arrays pick "uint16" by themselves
    np.testing.assert_array_equal(oiio_read_native(path)[0][:, :, 0], data)
    assert lio.read_metadata(path) == {}
    capture = lio.read_capture(path, camera=make_camera(cfa="RGGB", black_level=0, white_level=65535))
    np.testing.assert_allclose(capture.data * 65535.0, data, atol=1e-3)


def test_format_errors(tmp_path):
    image = np.zeros((2, 2), np.float32)
    cases = [
        (tmp_path / "a.bmp", image, None, "extension"),
        (tmp_path / "a.png", image, "tiff", "extension"),
        (tmp_path / "a.exr", image.astype(np.uint16), "uint16", "extension"),
        (tmp_path / "a.png", image, "uint16", "uint16"),
        (tmp_path / "a.tif", image, "webp", "unknown image format"),
        (tmp_path / "a.tif", np.zeros((2, 2, 5), np.float32), None, "channels"),
        (tmp_path / "a.tif", np.zeros((0, 3), np.float32), None, "shape"),
        (tmp_path / "a.jpg", np.zeros((2, 2, 2), np.float32), None, "JPEG"),
    ]
    for path, pixels, fmt, fragment in cases:
        with pytest.raises(LfprocError, match=fragment):
            lio.write_image(path, pixels, format=fmt)
    assert folder_is_empty(tmp_path)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("name", ["bad.tif", "bad.png", "bad.exr", "bad.jpg"])
def test_non_finite_images_are_refused_and_leave_nothing(tmp_path, name, bad):
    image = np.zeros((3, 3, 3), np.float32)
    image[1, 2, 0] = bad
    with pytest.raises(LfprocError, match="NaN or infinite") as info:
        lio.write_image(tmp_path / name, image, metadata={"a": 1.0})
    assert str(tmp_path / name) in str(info.value)
    assert folder_is_empty(tmp_path)


def test_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "keep.tif"
    lio.write_image(path, np.ones((2, 2), np.float32), metadata={"a": 0.0})
    before = path.read_bytes()
    real_output = oiio.ImageOutput

    class FailingOutput:                        # an encoder that fails half way through
        @staticmethod
        def create(name):
            real = real_output.create(name)

            class Wrapper:
                def open(self, *args):
                    return real.open(*args)

                def write_image(self, pixels):
                    real.write_scanline(0, 0, pixels[0])
                    return False

                def close(self):
                    return real.close()

                def geterror(self):
                    return "disk full (simulated)"
            return Wrapper()

    monkeypatch.setattr(oiio, "ImageOutput", FailingOutput)
    with pytest.raises(LfprocError, match="disk full"):
        lio.write_image(path, np.zeros((2, 2), np.float32), metadata={"a": 1.0})
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["keep.tif"]
    assert lio.read_metadata(path) == {"a": 0.0}


def test_write_into_missing_folder_creates_it_and_a_file_blocking_it_is_an_error(tmp_path):
    lio.write_image(tmp_path / "new" / "deep" / "x.exr", np.zeros((2, 2), np.float32))
    assert (tmp_path / "new" / "deep" / "x.exr").is_file()
    (tmp_path / "blocker").write_text("a file, not a folder")
    with pytest.raises(LfprocError, match="blocker"):
        lio.write_image(tmp_path / "blocker" / "x.tif", np.zeros((2, 2), np.float32))


# ===================================================================== GIF and sidecars

def test_write_gif_frames_and_timing(tmp_path):
    levels = [0.0, 0.18, 1.0]
    frames = [np.full((4, 6, 1), level, np.float32) for level in levels]
    path = tmp_path / "sweep.gif"
    lio.write_gif(path, frames, duration_ms=120)
    with Image.open(path) as gif:
        assert gif.n_frames == 3 and gif.size == (6, 4)
        assert gif.info.get("loop") == 0
        for k, level in enumerate(levels):
            gif.seek(k)
            assert gif.info["duration"] == 120
            grey = np.asarray(gif.convert("L"))
            assert np.all(grey == round(255 * srgb_reference(level)))
    colour = np.zeros((2, 3, 4, 3), np.float32)
    colour[1, ..., 0] = 1.0
    lio.write_gif(tmp_path / "colour.gif", colour, duration_ms=50)
    with Image.open(tmp_path / "colour.gif") as gif:
        gif.seek(1)
        np.testing.assert_array_equal(np.asarray(gif.convert("RGB"))[0, 0], [255, 0, 0])


def test_write_gif_refuses_bad_frames_and_leaves_nothing(tmp_path):
    path = tmp_path / "bad.gif"
    good = np.zeros((4, 4), np.float32)
    nan = good.copy()
    nan[0, 0] = np.nan
    for frames, duration, fragment in [([good, nan], 100, "NaN"), ([], 100, "no frames"),
                                       ([good, np.zeros((4, 5), np.float32)], 100, "shape"),
                                       ([good], 0, "duration"), ([good], float("nan"), "duration")]:
        with pytest.raises(LfprocError, match=fragment):
            lio.write_gif(path, frames, duration)
    assert folder_is_empty(tmp_path)


def test_sidecar_path_and_strict_json(tmp_path):
    assert lio.sidecar_path(os.path.join("out", "slice_a1.5.tif")) == os.path.join("out", "slice_a1.5.json")
    assert lio.sidecar_path(tmp_path / "v.exr") == str(tmp_path / "v.json")
    with pytest.raises(LfprocError):
        lio.sidecar_path("meta.json")
    written = lio.write_sidecar(tmp_path / "s.png", _metadata() | {"pos": np.array([0.5, -math.inf])})
    assert written == str(tmp_path / "s.json")
    text = (tmp_path / "s.json").read_text()
    assert _strict_loads(text) == {"source": "capture.dng", "a": 1.5, "distance_mm": 313.0661, "near_mm": 301.5,
                                   "far_mm": None, "dof_mm": None, "slice": 3, "view": [1, 2], "pos": [0.5, None]}
    assert sorted(os.listdir(tmp_path)) == ["s.json"]
    with pytest.raises(ValueError, match="NaN"):
        lio.write_sidecar(tmp_path / "n.tif", {"a": float("nan")})
    assert sorted(os.listdir(tmp_path)) == ["s.json"]


def test_metadata_must_be_a_dict(tmp_path):
    with pytest.raises(LfprocError, match="dict"):
        lio.write_image(tmp_path / "x.tif", np.zeros((2, 2), np.float32), metadata=[1, 2])
    assert folder_is_empty(tmp_path)


def test_describe_camera_raw_and_image(tmp_path):
    """``lfproc info``'s dict for a DNG (LibRaw's size and levels) and for a PNG (OpenImageIO's header)."""
    path = tmp_path / "capture.dng"
    write_dng(path, np.full((32, 48), 1000), BAYER_CODES["GRBG"], black=(10, 20, 30, 40), white=4095)
    info = lio.describe_file(path)
    assert (info["format"], info["raw_light_field"], info["width"], info["height"]) == ("camera-raw", True, 48, 32)
    assert info["white_level"] == 4095 and info["bits_per_pixel"] == 12 and sorted(info["black_level"]) == \
        [10, 20, 30, 40]
    oiio_write(tmp_path / "rgb.png", np.zeros((3, 7, 3), np.uint8), "uint8")
    info = lio.describe_file(tmp_path / "rgb.png")
    assert (info["format"], info["width"], info["height"], info["channels"], info["bits_per_pixel"]) == \
        ("image", 7, 3, 3, 8)
    with pytest.raises(LfprocError, match="not a readable image, camera raw or Lytro file"):
        (tmp_path / "junk.xyz").write_text("junk" * 10)
        lio.describe_file(tmp_path / "junk.xyz")


def test_a_gif_keeps_its_tags_whatever_their_length(tmp_path):
    """OpenImageIO reads one 255-byte block of a GIF comment: a wobble GIF written under a long path (pytest-xdist's
    temporary folders) was described as a raw light field."""
    from lfproc.io import write_gif_frames

    frames = [np.zeros((8, 8, 3), np.uint8)] * 2
    for length in (10, 400):
        path = write_gif_frames(tmp_path / "w.gif", frames, 100, {"source": "x" * length, "preview": "views"})
        info = lio.describe_file(path)
        assert (info["format"], info["raw_light_field"], info["tags"]["source"]) == ("lfproc-output", False,
                                                                                   "x" * length)
