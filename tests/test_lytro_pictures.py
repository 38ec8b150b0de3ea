"""Processed Lytro pictures of both generations: info, camera, export, the lambda map, refusals, the viewer.

Every picture is written here byte for byte (``lytropics``, ``h264pcm``); nothing depends on lfproc's
reader to build its input.
"""

from __future__ import annotations

import base64
import io
import json
import math

import numpy as np
import pytest

import lytrogen
import lytropics
from lytropics import cli, info_of
from conftest import assert_clean_error, run_cli

ILLUM_LAMBDAS = (-15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 12.5)
F01_LAMBDAS = (-8.92, -5.78, -2.6)


@pytest.fixture
def pictures(tmp_path):
    views = [(np.full((32, 48, 3), (40 + 60 * k, 120, 200 - 50 * k), np.uint8), 0.31 * (k - 1), 0.05 * k)
             for k in range(3)]
    depth = np.linspace(-9, 7, 12, dtype=np.float32).reshape(3, 4)
    depth[0, 0] = np.nan
    stack = lytropics.first_gen_stack(F01_LAMBDAS, parallax=views)
    return {"stk": lytropics.write(tmp_path / "IMG_0001-stk.lfp", stack),
            "dm": lytropics.write(tmp_path / "IMG_0001-dm.lfp", lytropics.first_gen_depth(depth)),
            "illum": lytropics.write(tmp_path / "IMG_0002.LFP", lytropics.illum_picture(ILLUM_LAMBDAS)),
            "views": views, "depth": depth}


# ----------------------------------------------------------------------------- info

def test_info_says_what_each_picture_holds(capsys, pictures):
    stk, dm, illum = (info_of(capsys, pictures[k]) for k in ("stk", "dm", "illum"))
    for info in (stk, dm, illum):
        assert {"format", "raw_light_field", "width", "height", "camera_model", "sections"} <= set(info)
        assert info["format"] == "lytro-container" and info["raw_light_field"] is False
        assert info["raw_frame"].startswith("referenced, not contained") and info["damaged"] is False
        assert info["raw_frame_reference"] == lytropics.RAW_REF and info["missing_sections"] == []
        assert all(s["sha1_ok"] for s in info["sections"])
    assert stk["picture"] == ["focus stack", "depth lookup table", "perspective views"]
    assert [i["lambda"] for i in stk["focus_stack"]["images"]] == list(F01_LAMBDAS)
    assert (stk["width"], stk["height"], stk["camera_model"], stk["serial"]) == (48, 48, "F01", "A502030123")
    assert stk["perspective_views"]["count"] == 3
    assert [(v["x"], v["y"]) for v in stk["perspective_views"]["views"]] == [(x, y) for _, x, y in pictures["views"]]
    assert dm["picture"] == ["depth map"] and (dm["width"], dm["height"]) == (4, 3)
    depth = pictures["depth"]
    assert (dm["depth_map"]["min_lambda"], dm["depth_map"]["max_lambda"]) == (np.nanmin(depth), np.nanmax(depth))
    assert illum["picture"] == ["focus stack", "depth map"] and illum["camera_model"] == "B01"
    assert [i["lambda"] for i in illum["focus_stack"]["images"]] == list(ILLUM_LAMBDAS)
    assert illum["serial"] == "B5143909630" and illum["lens"]["infinity_lambda"] == 200
    assert illum["lens"]["focal_length_mm"] == pytest.approx(77.59365439414978)
    assert illum["camera_known"] is True and illum["distance_from"] == "lambda"
    status, text, _ = cli(capsys, "info", pictures["illum"])
    assert status == 0 and "truncated" not in text and "referenced, not contained" in text


def test_truly_damaged_pictures_are_still_damaged(tmp_path, capsys):
    cut = lytropics.write(tmp_path / "cut-stk.lfp", lytropics.first_gen_stack(cut=700))
    status, _, err = cli(capsys, "info", cut)
    assert status == 2 and len(err) == 1 and "truncated" in err[0] and str(cut) in err[0]
    bad = lytropics.write(tmp_path / "bad.LFP", lytropics.illum_picture(corrupt=2))
    info = info_of(capsys, bad)
    assert info["damaged"] is True and [s["sha1_ok"] for s in info["sections"]].count(False) == 1
    status, _, err = cli(capsys, "export", bad, "-o", tmp_path / "out")
    assert status == 2 and len(err) == 1 and "fails its SHA-1 check" in err[0]
    assert not (tmp_path / "out").exists()
    # a stack image referenced but absent (unlike the raw frame, it belongs in the picture)
    data = lytropics.first_gen_stack()
    toc = json.loads(data[16 + 96:16 + 96 + int.from_bytes(data[28:32], "big")])
    missing = toc["picture"]["accelerationArray"][0]["vendorContent"]["imageArray"][1]["imageRef"]
    chunks = _chunks(data)
    gone = lytropics.write(tmp_path / "gone-stk.lfp",
                           lytropics.assemble(toc, [c for c in chunks if lytrogen.sha1_ref(c) != missing]))
    info = info_of(capsys, gone)
    assert info["damaged"] is True and info["missing_sections"] == [missing]
    status, _, err = cli(capsys, "export", gone, "-o", tmp_path / "out")
    assert status == 2 and len(err) == 1 and missing in err[0] and "missing" in err[0]


def _chunks(data: bytes) -> list[bytes]:
    """The LFC sections' data of a container (the test's own parse, for rebuilding one without a section)."""
    out, position = [], 16
    while position < len(data):
        length = int.from_bytes(data[position + 12:position + 16], "big")
        start = position + 96
        if data[position + 3:position + 4] == b"C":
            out.append(data[start:start + length])
        position = start + length + (-(start + length) % 16)
    return out


# ----------------------------------------------------------------------------- the lambda map

def _meta(kind):
    from lfproc.io._lytro_metadata import parse_metadata
    if kind == "illum":
        frame = lytrogen.fixture("illum-white-image.TXT")["master"]["picture"]["frameArray"][0]["frame"]
        return parse_metadata(frame["metadata"], frame["privateMetadata"], "illum")
    return parse_metadata(lytrogen.fixture("f01-frame.json"), None, "f01")


@pytest.mark.parametrize("kind", ["illum", "f01"])
def test_infinity_lambda_maps_to_the_slice_at_infinity(kind):
    """On the real metadata: infinityLambda is the model's slice at infinity (Illum: finite exit pupil)."""
    from lfproc import geometry
    from lfproc.io._lytro_lambda import lambda_map

    meta = _meta(kind)
    mapping = lambda_map(meta)
    cam = mapping.camera
    assert mapping.a(meta.infinity_lambda) == pytest.approx(geometry.infinity_parameter(cam), rel=1e-12)
    assert math.isinf(mapping.distance_mm(meta.infinity_lambda))
    assert math.isinf(mapping.distance_mm(meta.infinity_lambda + 3))            # beyond infinity
    assert math.isfinite(geometry.slice_distance_mm(cam, mapping.a(meta.infinity_lambda - 1e-3)))
    assert cam.main_optics.image_distance_mm - cam.main_optics.focal_length_mm == pytest.approx(
        meta.infinity_lambda * meta.f_number * meta.lens_pitch_m * 1e3, rel=1e-12)
    assert dict(cam.provenance)["main_lens.image_distance_mm"].startswith("derived from lambda")


@pytest.mark.parametrize("kind", ["illum", "f01"])
def test_lambda_distances_are_the_thin_lens_image_of_the_defocused_plane(kind):
    """Independent closed form: the plane (λ_∞ − λ)·N·p_m behind the back focal plane images at
    x = f_U²/x' in front of the front focal plane (Newton); the distance from the sensor adds f_s + b_U + f_U."""
    from lfproc.io._lytro_lambda import lambda_map

    meta = _meta(kind)
    mapping = lambda_map(meta)
    f_u, n, p_m = meta.focal_length_m * 1e3, meta.f_number, meta.lens_pitch_m * 1e3
    b_u = f_u + meta.infinity_lambda * n * p_m
    for lam in (-15.0, -8.92, -2.6, 0.0, 5.0, meta.infinity_lambda - 0.5):
        x = f_u ** 2 / ((meta.infinity_lambda - lam) * n * p_m)
        expected = meta.sensor_offset_m[2] * 1e3 + b_u + f_u + x
        assert mapping.distance_mm(lam) == pytest.approx(expected, rel=1e-9)


def test_stack_lambdas_span_the_refocus_range_of_the_model():
    """Evidence for the unit: the stacks' lambda ranges (Illum −15 … 12.5, F01 −8.92 …) are |a| of about 1,
    the range shift-and-sum refocuses over; a unit m̂ times larger or smaller would put them far outside."""
    from lfproc.io._lytro_lambda import lambda_map

    illum, f01 = lambda_map(_meta("illum")), lambda_map(_meta("f01"))
    assert 0.8 < max(abs(illum.a(-15.0)), abs(illum.a(12.5))) < 1.5
    assert 0.8 < abs(f01.a(-8.92)) < 1.5


# ----------------------------------------------------------------------------- export

def test_export_stack_depth_and_views(tmp_path, capsys, pictures):
    from lfproc.io import read_image, read_metadata, srgb_decode
    from lfproc.io._lytro_lambda import lambda_map
    from lfproc.io import open_picture, picture_metadata

    out = tmp_path / "out"
    status, _, err = cli(capsys, "export", pictures["stk"], pictures["dm"], pictures["illum"], "-o", out, "--tiff")
    assert status == 0, err
    mapping = lambda_map(picture_metadata(open_picture(str(pictures["illum"])))[0])
    original = lytropics.illum_picture(ILLUM_LAMBDAS)
    for k, lam in enumerate(ILLUM_LAMBDAS):
        sidecar = json.loads((out / f"IMG_0002_stack_{k:02d}.json").read_text())
        assert sidecar["source"] == str(pictures["illum"]) and sidecar["lambda"] == lam
        assert sidecar["distance_from"] == "lambda" and sidecar["a"] == pytest.approx(mapping.a(lam), rel=1e-12)
        assert sidecar["distance_mm"] == pytest.approx(float(mapping.distance_mm(lam)), rel=1e-12)
        assert sidecar["near_mm"] < sidecar["distance_mm"] < sidecar["far_mm"]
        assert sidecar["dof_mm"] == pytest.approx(sidecar["far_mm"] - sidecar["near_mm"])
        jpeg = (out / f"IMG_0002_stack_{k:02d}.jpg").read_bytes()
        stored = lytropics.jpeg(lytropics.focus_scene(len(ILLUM_LAMBDAS))[k])
        assert stored in original and _without_metadata(jpeg) == stored     # the JPEG as it is
        assert read_metadata(out / f"IMG_0002_stack_{k:02d}.jpg") == sidecar
        assert read_metadata(out / f"IMG_0002_stack_{k:02d}.tif") == sidecar
        from PIL import Image
        decoded = np.asarray(Image.open(io.BytesIO(stored)).convert("RGB"), np.float32) / 255
        np.testing.assert_allclose(read_image(out / f"IMG_0002_stack_{k:02d}.tif"), srgb_decode(decoded), atol=1e-6)
    import tifffile
    lam = tifffile.imread(out / "IMG_0001-dm_depth_lambda.tif")
    np.testing.assert_array_equal(lam, pictures["depth"])                      # NaN where NaN
    depth = tifffile.imread(out / "IMG_0001-dm_depth.tif")
    f01 = lambda_map(_meta("f01"))
    assert np.isnan(depth[0, 0]) and math.isinf(depth[-1, -1])                 # unknown; λ = λ_∞ = 7
    np.testing.assert_allclose(depth[1], f01.distance_mm(pictures["depth"][1]).astype(np.float32), rtol=1e-6)
    meta = json.loads((out / "IMG_0001-dm_depth.json").read_text())
    assert (meta["unit"], meta["distance_from"]) == ("mm", "lambda")
    assert json.loads((out / "IMG_0001-dm_depth_lambda.json").read_text())["unit"] == "lambda"
    assert (out / "IMG_0001-dm_depth_preview.png").stat().st_size > 0
    assert (out / "IMG_0001-dm_depth_confidence.tif").exists()
    for k, (rgb, x, y) in enumerate(pictures["views"]):
        view = read_image(out / f"IMG_0001-stk_parallax_{k:02d}.tif")
        np.testing.assert_allclose(view, srgb_decode(rgb / 255.0), atol=0.02)  # YCbCr 8-bit round trip
        assert json.loads((out / f"IMG_0001-stk_parallax_{k:02d}.json").read_text())["coord"] == [x, y]
    # lfproc info prints a nested tag (the exported depth map's camera) as its own lines, not a Python dict
    nested = [k for k, v in meta.items() if isinstance(v, dict)]
    assert nested
    status, text, _ = cli(capsys, "info", out / "IMG_0001-dm_depth.tif")
    assert status == 0 and "{'" not in text and f"  {nested[0]}:" in text


def _without_metadata(jpeg: bytes) -> bytes:
    """The JPEG minus the COM and Exif APP1 segments export inserts."""
    out, position = bytearray(jpeg[:2]), 2
    while jpeg[position] == 0xFF and (0xE0 <= jpeg[position + 1] <= 0xEF or jpeg[position + 1] == 0xFE):
        length = 2 + int.from_bytes(jpeg[position + 2:position + 4], "big")
        if jpeg[position + 1] == 0xE0:
            out += jpeg[position:position + length]
        position += length
    return bytes(out + jpeg[position:])


def test_export_without_camera_metadata_gives_lambda_only(tmp_path, capsys):
    pic = lytropics.write(tmp_path / "IMG-stk.lfp", lytropics.first_gen_stack(with_metadata=False))
    status, _, err = cli(capsys, "export", pic, "-o", tmp_path / "out")
    assert status == 0, err
    sidecar = json.loads((tmp_path / "out" / "IMG-stk_stack_00.json").read_text())
    assert sidecar["lambda"] == F01_LAMBDAS[0] and "distance_mm" not in sidecar and "a" not in sidecar
    assert sidecar["camera_note"].startswith("no distances")
    assert (tmp_path / "out" / "IMG-stk_depth_lambda.tif").exists()
    assert not (tmp_path / "out" / "IMG-stk_depth.tif").exists()


def test_illum_depth_map_stored_as_an_image(tmp_path):
    from lfproc.io import depth_lambda, open_picture

    depth = np.linspace(-15, 12.5, 256, dtype=np.float32).reshape(16, 16)
    pic = lytropics.write(tmp_path / "png.LFP", lytropics.illum_picture(depth=depth, depth_as_png=True))
    np.testing.assert_allclose(depth_lambda(open_picture(str(pic))), depth, atol=27.5 / 255 / 2 + 1e-5)


def test_damaged_h264_block_is_one_line(tmp_path, capsys):
    from lfproc.io._lytro_h264 import decode_h264
    from lfproc.errors import LfprocError

    with pytest.raises(LfprocError, match="no frames|cannot open"):
        decode_h264(bytes(range(256)) * 4, "x.lfp")


def test_export_refuses_captures_and_other_files(tmp_path, capsys):
    raw = lytrogen.write_container(tmp_path / "IMG.lfr", np.full((6, 8), 500), 10, "little",
                                   *lytrogen.frame_metadata_of(lytrogen.illum_document(8, 6)))
    status, _, err = cli(capsys, "export", raw, "-o", tmp_path / "out")
    assert status == 2 and len(err) == 1 and "holds the raw light field" in err[0]
    (tmp_path / "a.txt").write_text("x")
    status, _, err = cli(capsys, "export", tmp_path / "a.txt", "-o", tmp_path / "out")
    assert status == 2 and len(err) == 1 and "not a Lytro picture" in err[0]
    assert not (tmp_path / "out").exists()


# ----------------------------------------------------------------------------- camera, refusals

def test_camera_file_from_an_illum_picture(tmp_path, capsys, pictures):
    import tomllib

    from lfproc import Camera

    out = tmp_path / "cam.toml"
    status, _, err = cli(capsys, "camera", pictures["illum"], "-o", out)
    assert status == 0, err
    cam = Camera.from_toml(out)
    devices = lytrogen.fixture("illum-white-image.TXT")["master"]["picture"]["frameArray"][0]["frame"]["metadata"][
        "devices"]
    assert cam.main_optics.focal_length_mm == pytest.approx(devices["lens"]["focalLength"] * 1e3, rel=1e-12)
    assert cam.mla_focal_length_mm == pytest.approx(devices["mla"]["sensorOffset"]["z"] * 1e3, rel=1e-12)
    assert dict(cam.provenance) == tomllib.loads(out.read_text())["provenance"]
    assert dict(cam.provenance)["mla.pitch_mm"] == "metadata: devices.mla.lensPitch"
    assert "lambda reading" in out.read_text()
    no_meta = lytropics.write(tmp_path / "x-stk.lfp", lytropics.first_gen_stack(with_metadata=False))
    status, _, err = cli(capsys, "camera", no_meta, "-o", tmp_path / "c2.toml")
    assert status == 2 and len(err) == 1 and "does not describe the camera" in err[0]


@pytest.mark.parametrize("command", ["decode", "depth", "views"])
def test_raw_light_field_commands_refuse_pictures(tmp_path, command, pictures, paper_camera):
    from lfproc import Camera, simulate

    grid = simulate.default_grid(Camera.from_toml(paper_camera), (100, 100))
    (tmp_path / "grid.json").write_text(json.dumps(grid.to_json_dict()))
    out = tmp_path / ("out.lfp.npz" if command == "decode" else "out")
    proc = run_cli(command, pictures["illum"], "--camera", paper_camera, "--calib", tmp_path / "grid.json", "-o", out)
    assert_clean_error(proc, str(pictures["illum"]), "processed Lytro picture", "a focus stack and a depth map",
                       "lfproc export", "raw .lfp/.lfr")
    assert not out.exists()


def test_batch_and_viewer_refuse_pictures_without_a_stack(tmp_path, pictures, paper_camera):
    from lfproc import Camera, simulate

    grid = simulate.default_grid(Camera.from_toml(paper_camera), (100, 100))
    (tmp_path / "grid.json").write_text(json.dumps(grid.to_json_dict()))
    proc = run_cli("batch", pictures["dm"], "--camera", paper_camera, "--calib", tmp_path / "grid.json", "--a", "0",
                   "-o", tmp_path / "b")
    assert_clean_error(proc, str(pictures["dm"]), "processed Lytro picture (a depth map)", "lfproc export")
    assert not (tmp_path / "b").exists()
    proc = run_cli("viewer", pictures["dm"], "-o", tmp_path / "v")
    assert_clean_error(proc, str(pictures["dm"]), "processed Lytro picture", "no focus stack", "lfproc export")


# ----------------------------------------------------------------------------- viewer

def _page_data(path) -> dict:
    text = path.read_text()
    start = text.index('id="lfproc-data">') + len('id="lfproc-data">')
    return json.loads(text[start:text.index("</script>", start)])


def test_viewer_shows_the_sharpest_stack_image_where_clicked(tmp_path, capsys, pictures):
    status, _, err = cli(capsys, "viewer", pictures["stk"], pictures["illum"], "-o", tmp_path / "v")
    assert status == 0, err
    assert "IMG_0001-stk/index.html" in (tmp_path / "v" / "index.html").read_text()
    for stem, count in (("IMG_0001-stk", len(F01_LAMBDAS)), ("IMG_0002", len(ILLUM_LAMBDAS))):
        page = tmp_path / "v" / stem / "index.html"
        data = _page_data(page)
        assert "http://" not in page.read_text() and "https://" not in page.read_text()
        choice = np.frombuffer(base64.b64decode(data["choice"]["base64"]), np.uint8).reshape(data["choice"]["shape"])
        assert len(data["images"]) == count
        for image in data["images"]:
            assert (page.parent / image["image"]).exists()
        if stem == "IMG_0001-stk":    # no depth map: sharpness; image k is sharp in vertical band k of 3
            rows, cols = choice.shape
            for k in range(count):
                band = choice[:, int((k + 0.5) * cols / count)]
                assert (band == k).all(), (k, choice)
            assert "Laplacian" in data["method"]
        else:                         # the depth map (a ramp from −15 to 12.5 in lambda) picks the nearest lambda
            from lfproc.io import depth_lambda, open_picture
            lam = depth_lambda(open_picture(str(pictures["illum"])))
            nearest = np.argmin(np.abs(lam[..., None] - np.array(ILLUM_LAMBDAS)), axis=-1)
            np.testing.assert_array_equal(choice, nearest)
            assert choice[0, 0] == 0 and choice[-1, -1] == count - 1
            assert data["images"][0]["distance_from"] == "lambda" and data["images"][0]["distance_mm"] > 0


def test_a_picture_of_an_unknown_kind_is_not_called_truncated(tmp_path, capsys):
    from lfproc.errors import LfprocError
    from lfproc.io import read_lytro

    toc = {"picture": {"frameArray": [{"frame": {"imageRef": lytropics.RAW_REF}}],
                       "accelerationArray": [{"type": "com.lytro.acceleration.somethingNew", "vendorContent": {}}]}}
    path = lytropics.write(tmp_path / "new.lfp", lytropics.assemble(toc, [b"abc"]))
    info = info_of(capsys, path)
    assert info["raw_light_field"] is False and "truncated" not in json.dumps(info)
    with pytest.raises(LfprocError, match="kind lfproc does not read") as caught:
        read_lytro(path)
    assert "truncated" not in str(caught.value)
