"""Lytro files at the byte level: packings against bit-level references, containers, metadata, bad input.

Every file is written by the test (tests/lytrogen.py) as lytro-format.md describes it; no real raw
image is needed. The metadata starts from the two real fixtures' JSON.
"""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np
import pytest

import lytrogen
from lfproc import io as lio
from lfproc.errors import LfprocError
from lfproc.camera import MainLens


# ============================================================================ packings

def reference_unpack_10_little(data: bytes, count: int) -> list[int]:
    """Plain Python, pixel by pixel, as the format text says."""
    out = []
    for i in range(count):
        group, k = divmod(i, 4)
        base = 5 * group
        out.append((data[base + k] << 2) | ((data[base + 4] >> (2 * k)) & 3))
    return out


def reference_unpack_12_big(data: bytes, count: int) -> list[int]:
    out = []
    for i in range(count):
        group, k = divmod(i, 2)
        b0, b1, b2 = data[3 * group:3 * group + 3]
        out.append(b0 * 16 + (b1 >> 4) if k == 0 else (b1 & 15) * 256 + b2)
    return out


def unpackbits_12_big(data: bytes) -> np.ndarray:
    """12-bit big-endian as one MSB-first bit stream cut every 12 bits (numpy.unpackbits)."""
    bits = np.unpackbits(np.frombuffer(data, np.uint8)).reshape(-1, 12)
    return bits.dot(1 << np.arange(11, -1, -1))


@pytest.mark.parametrize("seed", [0, 1])
def test_10bit_little_matches_a_python_loop(seed):
    rng = np.random.default_rng(seed)
    data = rng.integers(0, 256, size=5 * 100, dtype=np.uint8).tobytes()     # 400 pixels, every bit pattern
    got = lio.unpack_raw(data, 20, 20, 10, "little")
    assert got.dtype == np.uint16 and got.shape == (20, 20)
    assert got.ravel().tolist() == reference_unpack_10_little(data, 400)


def unpackbits_10_little(data: bytes) -> np.ndarray:
    """10-bit little-endian from the bits (numpy.unpackbits, MSB first per byte): pixel i of a group is byte i's
    8 bits then bits 2i+1 and 2i of byte 4."""
    bits = np.unpackbits(np.frombuffer(data, np.uint8)).reshape(-1, 5, 8).astype(np.int64)
    msb = bits[:, :4, :].dot(1 << np.arange(7, -1, -1))                     # (N, 4)
    low = np.stack([bits[:, 4, 7 - (2 * i + 1)] * 2 + bits[:, 4, 7 - 2 * i] for i in range(4)], axis=1)
    return (msb * 4 + low).ravel()


def test_10bit_little_over_several_blocks_matches_unpackbits():
    rng = np.random.default_rng(3)
    groups = 3 * 65536 + 7                                   # more than one of the reader's blocks, a ragged end
    data = rng.integers(0, 256, size=5 * groups, dtype=np.uint8).tobytes()
    got = lio.unpack_raw(data, groups, 4, 10, "little")          # 4 rows of `groups` pixels
    np.testing.assert_array_equal(got.ravel(), unpackbits_10_little(data))


@pytest.mark.parametrize("seed", [0, 1])
def test_12bit_big_matches_a_python_loop_and_unpackbits(seed):
    rng = np.random.default_rng(seed)
    data = rng.integers(0, 256, size=3 * 150, dtype=np.uint8).tobytes()     # 300 pixels
    got = lio.unpack_raw(data, 30, 10, 12, "big")
    assert got.ravel().tolist() == reference_unpack_12_big(data, 300)
    np.testing.assert_array_equal(got.ravel(), unpackbits_12_big(data))


@pytest.mark.parametrize("bits, order, top", [(10, "little", 1023), (12, "big", 4095)])
def test_packing_round_trip_extremes(bits, order, top):
    dn = np.array([[0, top, 1, top - 1], [2 ** (bits - 1), 3, top, 0]], np.uint16)
    got = lio.unpack_raw(lytrogen.pack(dn, bits, order), 4, 2, bits, order)
    np.testing.assert_array_equal(got, dn)


def test_known_bytes_of_the_format_text():
    # pixels 0..3 = 0b1111111111, 0, 0b0000000001, 0b1000000010: MSBs 255, 0, 0, 128; LSBs 3, 0, 1, 2
    data = bytes([255, 0, 0, 128, 0b10_01_00_11])
    assert lio.unpack_raw(data, 4, 1, 10, "little").ravel().tolist() == [1023, 0, 1, 514]
    # F01: pixel 0 = 0xAB·16 + 0xC = 0xABC, pixel 1 = 0xD·256 + 0xEF = 0xDEF
    assert lio.unpack_raw(bytes([0xAB, 0xCD, 0xEF]), 2, 1, 12, "big").ravel().tolist() == [0xABC, 0xDEF]


def test_unknown_packing_and_wrong_size_are_one_line_errors():
    with pytest.raises(LfprocError, match="unknown raw packing .*12 bits.*little"):
        lio.unpack_raw(bytes(30), 4, 5, 12, "little", source="x.raw")
    with pytest.raises(LfprocError, match=r"x.raw: the metadata says 4 x 5 pixels at 10 bits \(25 bytes\) but the "
                                          r"raw data holds 24 bytes"):
        lio.unpack_raw(bytes(24), 4, 5, 10, "little", source="x.raw")


# ============================================================================ containers

def small_illum(tmp_path, name="cap.lfr", **kwargs):
    rng = np.random.default_rng(5)
    dn = rng.integers(64, 1024, size=(6, 8)).astype(np.uint16)
    doc = lytrogen.illum_document(8, 6)
    meta, private = lytrogen.frame_metadata_of(doc)
    path = lytrogen.write_container(tmp_path / name, dn, 10, "little", meta, private, **kwargs)
    return path, dn


def test_container_sections_follow_the_format(tmp_path):
    path, dn = small_illum(tmp_path)
    data = path.read_bytes()
    info = lio.describe_file(path)
    assert info["format"] == "lytro-container" and info["raw_light_field"] is True
    assert info["camera_model"] == "B01" and info["serial"] == "B5143909630"
    assert (info["width"], info["height"], info["bits_per_pixel"], info["cfa"]) == (8, 6, 10, "GRBG")
    kinds = [s["kind"] for s in info["sections"]]
    assert kinds == ["LFM", "LFC", "LFC", "LFC", "LFC"]
    raw = next(s for s in info["sections"] if s["content"] == "raw sensor image (packed)")
    assert raw["length"] == 6 * 8 * 10 // 8 and raw["sha1_ok"]
    assert raw["sha1"] == "sha1-" + hashlib.sha1(lytrogen.pack10_little(dn)).hexdigest()
    assert {s["content"] for s in info["sections"]} >= {"table of contents (JSON)", "frame metadata (JSON)",
                                                         "private metadata (JSON: serial numbers)"}
    assert len(data) % 16 == 0
    capture = lio.read_capture(path)
    assert capture.cfa == "GRBG"
    np.testing.assert_allclose(capture.data, (dn - 64.0) / (1023.0 - 64.0), rtol=1e-6)


def test_the_raw_frame_is_found_by_reference_not_position(tmp_path):
    """A first frame whose image is not in the file is passed over; the raw chunk is the third chunk."""
    path, dn = small_illum(tmp_path, frame_without_raw_first=True)
    np.testing.assert_allclose(lio.read_capture(path).data, (dn - 64.0) / 959.0, rtol=1e-6)


@pytest.mark.parametrize("extension", [".LFR", ".lfp", ".LFP", ".bin"])
def test_any_case_extension_and_magic(tmp_path, extension):
    path, dn = small_illum(tmp_path, "cap" + extension)
    np.testing.assert_allclose(lio.read_capture(path).data, (dn - 64.0) / 959.0, rtol=1e-6)


def test_f01_raw_pair_levels_per_channel_and_bggr(tmp_path):
    rng = np.random.default_rng(7)
    dn = rng.integers(0, 4096, size=(4, 6)).astype(np.uint16)
    black = {"r": 100, "gr": 110, "gb": 120, "b": 130}
    white = {"r": 4000, "gr": 4010, "gb": 4020, "b": 4095}
    meta = lytrogen.f01_metadata(6, 4, black=black, white=white)
    path = lytrogen.write_raw_pair(tmp_path / "frame.RAW", dn, 12, "big", meta, ".json")
    capture = lio.read_capture(path)
    assert capture.cfa == "BGGR"
    # BGGR: (0,0) b, (0,1) gb, (1,0) gr, (1,1) r (the tile r,gr:gb,b shifted so b is upper left)
    names = [["b", "gb"], ["gr", "r"]]
    expected = np.empty(dn.shape)
    for y in range(4):
        for x in range(6):
            name = names[y % 2][x % 2]
            expected[y, x] = (int(dn[y, x]) - black[name]) / (white[name] - black[name])
    np.testing.assert_allclose(capture.data, expected, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("upper_left, cfa", [("r", "RGGB"), ("gr", "GRBG"), ("gb", "GBRG"), ("b", "BGGR")])
def test_bayer_layout_from_upper_left_pixel(tmp_path, upper_left, cfa):
    meta = lytrogen.f01_metadata(4, 2)
    meta["image"]["rawDetails"]["mosaic"]["upperLeftPixel"] = upper_left
    path = lytrogen.write_raw_pair(tmp_path / "f.raw", np.full((2, 4), 1000), 12, "big", meta, ".txt")
    assert lio.read_capture(path).cfa == cfa


def test_metadata_of_both_fixtures():
    illum = lytrogen.fixture("illum-white-image.TXT")
    from lfproc.io._lytro_metadata import frame_metadata, parse_metadata
    meta, private, modulation = frame_metadata(illum, "illum.TXT")
    m = parse_metadata(meta, private, "illum.RAW", modulation)
    assert (m.model, m.serial, m.width, m.height, m.bits_per_pixel, m.endianness) == \
        ("B01", "B5143909630", 7728, 5368, 10, "little")
    assert m.cfa == "GRBG" and m.modulation_frame is True and m.packed_bytes == 7728 * 5368 * 10 // 8
    assert (m.zoom_step, m.focus_step) == (-1040, -300)
    assert not m.exit_pupil_at_infinity and m.exit_pupil_offset_m == pytest.approx(0.046048875898122787)
    f01 = lytrogen.fixture("f01-frame.json")
    meta, private, modulation = frame_metadata(f01, "f01.json")
    m = parse_metadata(meta, private, "f01.raw", modulation)
    assert (m.model, m.serial, m.cfa, m.bits_per_pixel) == ("F01", None, "BGGR", 12)
    assert m.exit_pupil_at_infinity and np.all(m.levels()[0] == 168) and np.all(m.levels()[1] == 4095)


# ============================================================================ bad input

def expect_error(path, *fragments):
    with pytest.raises(LfprocError) as info:
        lio.read_capture(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message, message
    for fragment in fragments:
        assert fragment in message, message


def test_truncated_container(tmp_path):
    path, _ = small_illum(tmp_path)
    data = path.read_bytes()
    for keep in (10, 150, len(data) - 100):
        cut = tmp_path / f"cut{keep}.lfr"
        cut.write_bytes(data[:keep])
        expect_error(cut, "re-copy")
    expect_error(_write(tmp_path / "junk.lfr", b"not a container" * 4), "not a Lytro container")


def _write(path, data):
    path.write_bytes(data)
    return path


def test_sha1_mismatch(tmp_path):
    path, _ = small_illum(tmp_path, bad_sha1=True)
    expect_error(path, "fails its SHA-1 check", "corrupt")
    info = lio.describe_file(path)      # described, with the bad section marked
    assert [s["sha1_ok"] for s in info["sections"]].count(False) == 1 and info["raw_light_field"] is False


def test_container_without_raw_image(tmp_path):
    path = _write(tmp_path / "IMG_0001-stk.lfp", lytrogen.processed_picture_bytes())
    expect_error(path, "holds no raw light field", "processed Lytro picture")
    info = lio.describe_file(path)
    assert info["format"] == "lytro-container" and info["raw_light_field"] is False
    assert info["sections"][0]["kind"] == "LFM" and len(info["sections"]) == 5


def test_metadata_contradicting_the_data_size(tmp_path):
    doc = lytrogen.illum_document(8, 8)       # says 8 x 8, the raw holds 8 x 6
    path = lytrogen.write_raw_pair(tmp_path / "MOD_0000.RAW", np.full((6, 8), 500), 10, "little", doc)
    expect_error(path, "8 x 8 pixels at 10 bits (80 bytes) but the raw data holds 60 bytes")
    info = lio.describe_file(path)       # described, the mismatch said
    assert info["size_matches_metadata"] is False and info["raw_light_field"] is False


def test_unknown_packing(tmp_path):
    doc = lytrogen.illum_document(8, 6)
    doc["master"]["picture"]["frameArray"][0]["frame"]["metadata"]["image"]["rawDetails"]["pixelPacking"] = \
        {"endianness": "little", "bitsPerPixel": 14}
    path = lytrogen.write_raw_pair(tmp_path / "MOD_0001.RAW", np.full((6, 8), 500), 10, "little", doc)
    expect_error(path, "unknown raw packing (14 bits per pixel, little-endian)")


def test_raw_without_metadata_is_not_taken_for_a_lytro_file(tmp_path):
    path = _write(tmp_path / "lonely.raw", bytes(60))
    expect_error(path, "a Lytro .raw needs its metadata NAME.txt or NAME.json beside it")


def test_metadata_that_is_not_json(tmp_path):
    path = _write(tmp_path / "x.raw", bytes(60))
    (tmp_path / "x.txt").write_text("not json {")
    with pytest.raises(LfprocError, match="x.txt: metadata is not valid JSON"):   # names the faulty file
        lio.read_capture(path)


def test_camera_file_levels_are_not_used_for_lytro_files(tmp_path):
    from lfproc.camera import Camera
    path, dn = small_illum(tmp_path)
    cam = Camera(0.0014, 0.02, 0.04, MainLens(77.0, 77.0), cfa="RGGB", black_level=0, white_level=65535)
    capture = lio.read_capture(path, cam)
    assert capture.cfa == "GRBG"
    np.testing.assert_allclose(capture.data, (dn - 64.0) / 959.0, rtol=1e-6)


def test_describe_images_and_strict_json(tmp_path):
    from lfproc.io import write_image
    write_image(tmp_path / "a.png", np.zeros((3, 5), np.uint16))
    info = lio.describe_file(tmp_path / "a.png")
    assert (info["format"], info["width"], info["height"], info["bits_per_pixel"]) == ("image", 5, 3, 16)
    f01 = lytrogen.f01_metadata(4, 2)
    path = lytrogen.write_raw_pair(tmp_path / "f.raw", np.full((2, 4), 1000), 12, "big", f01, ".json")
    info = lio.describe_file(path)
    assert info["format"] == "lytro-raw" and info["lens"]["exit_pupil_distance_mm"] == math.inf
    json.dumps(lio.describe_file(path), allow_nan=True)


def test_describe_a_decoded_light_field(tmp_path):
    from lfproc import Camera, LightField
    from conftest import SAMPLES
    camera = Camera.from_toml(SAMPLES / "cameras" / "paper-f100.toml")
    LightField.from_views(np.zeros((25, 25, 3, 4, 2), np.float32), camera).save(tmp_path / "x.lfp.npz")
    info = lio.describe_file(tmp_path / "x.lfp.npz")
    assert (info["format"], info["raw_light_field"], info["width"], info["height"], info["views"],
            info["channels"]) == ("lightfield", False, 4, 3, 25, 2)
