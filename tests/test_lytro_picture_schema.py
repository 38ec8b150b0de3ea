"""Lytro pictures as real cameras write them: the Illum picture schema, stacks stored as H.264 beside a
parallax block, the camera given to export, views as JPEG and GIF, lambda previews, the viewer of views,
exported images recognised, a container whose raw image was removed, napari-LF metadata.

Every picture is written here byte for byte (``lytropics``, ``h264pcm``); expected distances come from the
thin-lens (Newton) closed form, not from lfproc's lambda map.
"""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest

import lytrogen
import lytropics
from lytropics import cli, illum_thin_lens, info_of

ILLUM_LAMBDAS = (-15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 12.5)
STACK_LAMBDAS = tuple(np.round(np.linspace(-8.9, 5.0, 11), 3))


def newton_distance(lam, *, f_u, n, p_m, f_s, b_u):
    """Distance from the sensor of the object imaged at lambda (docs/lytro.md, steps 2-3): the image plane
    lies x' = b_U − f_U − λ·N·p_m behind the back focal plane, its object x = f_U²/x' before the front one."""
    x_image = b_u - f_u - lam * n * p_m
    return math.inf if x_image <= 0 else f_s + b_u + f_u + f_u ** 2 / x_image


def views(count=4, size=(32, 48)):
    """Distinct flat colours at (±0.3, 0), (0, ±0.3) (four) or on a ring (more)."""
    out = []
    for k in range(count):
        angle = 2 * math.pi * k / count
        colour = (30 + 200 * k // count, 220 - 180 * k // count, 60 + (97 * k) % 150)
        out.append((np.full(size + (3,), colour, np.uint8), round(0.3 * math.cos(angle), 6),
                    round(0.3 * math.sin(angle), 6)))
    return out


# ----------------------------------------------------------------------------- the Illum picture schema

@pytest.fixture
def illum(tmp_path):
    data, toc = lytropics.illum_picture_from_toc(lytropics.illum_schema_toc(ILLUM_LAMBDAS))
    return lytropics.write(tmp_path / "IMG_0480.LFP", data), toc


def test_illum_schema_info_and_camera_file(tmp_path, capsys, illum):
    from lfproc import Camera

    path, toc = illum
    metadata = toc["frames"][0]["frame"]["metadata"]
    lens = metadata["devices"]["lens"]
    info = info_of(capsys, path)
    assert info["camera_model"] == "ILLUM" and info["serial"] == "B5143909630" and info["camera_known"] is True
    assert info["lens"]["focal_length_mm"] == pytest.approx(lens["focalLength"] * 1e3, rel=1e-12)
    assert info["cfa"] == "GRBG" and info["raw_frame_width"] == 7728
    status, text, _ = cli(capsys, "info", path)
    assert status == 0 and "ILLUM" in text and "rawDetails" not in text
    out = tmp_path / "cam.toml"
    status, _, err = cli(capsys, "camera", path, "-o", out)
    assert status == 0, err
    cam = Camera.from_toml(out)
    assert cam.main_optics.focal_length_mm == pytest.approx(lens["focalLength"] * 1e3, rel=1e-12)
    assert cam.main_optics.f_number == lens["fNumber"] and cam.cfa == "GRBG" and cam.black_level == 64
    tables = tomllib.loads(out.read_text())
    numbers = {f"{t}.{k}" for t, table in tables.items() if t != "provenance" and isinstance(table, dict)
               for k in table}
    assert numbers <= set(tables["provenance"]), numbers - set(tables["provenance"])
    assert tables["provenance"]["sensor.cfa"] == "metadata: image.mosaic.upperLeftPixel"
    assert tables["provenance"]["sensor.black_level"] == "metadata: image.pixelFormat.black"


def test_illum_schema_export_in_mm(tmp_path, capsys, illum):
    import tifffile

    path, toc = illum
    lens = illum_thin_lens(toc)
    f_u, n, p_m, f_s, b_u = (lens[k] for k in ("f_u", "n", "p_m", "f_s", "b_u"))
    status, _, err = cli(capsys, "export", path, "-o", tmp_path / "out")
    assert status == 0, err
    for k, lam in enumerate(ILLUM_LAMBDAS):
        sidecar = json.loads((tmp_path / "out" / f"IMG_0480_stack_{k:02d}.json").read_text())
        assert sidecar["lambda"] == lam and sidecar["camera_model"] == "ILLUM"
        assert sidecar["distance_mm"] == pytest.approx(newton_distance(lam, f_u=f_u, n=n, p_m=p_m, f_s=f_s, b_u=b_u),
                                                       rel=1e-9)
        assert sidecar["near_mm"] < sidecar["distance_mm"] < sidecar["far_mm"]
        assert sidecar["dof_mm"] == pytest.approx(sidecar["far_mm"] - sidecar["near_mm"]) and "a" in sidecar
        assert sidecar["provenance"]["inputs"]["capture"]["path"] == str(path)
    lam = tifffile.imread(tmp_path / "out" / "IMG_0480_depth_lambda.tif")
    depth = tifffile.imread(tmp_path / "out" / "IMG_0480_depth.tif")
    assert lam.shape == (8, 12)
    expected = [newton_distance(v, f_u=f_u, n=n, p_m=p_m, f_s=f_s, b_u=b_u) for v in lam.ravel()]
    np.testing.assert_allclose(depth.ravel(), np.array(expected, np.float32), rtol=1e-5)
    assert json.loads((tmp_path / "out" / "IMG_0480_depth.json").read_text())["unit"] == "mm"
    assert json.loads((tmp_path / "out" / "IMG_0480_depth_lambda.json").read_text())["unit"] == "lambda"


# ----------------------------------------------------------------------------- stack (H.264) + parallax

def test_h264_refocus_stack_beside_a_parallax_block_exports_both(tmp_path, capsys):
    from lfproc.io import read_image, srgb_decode

    parallax = views(4)
    path = lytropics.write(tmp_path / "IMG_0009-stk.lfp", lytropics.first_gen_h264_stack(STACK_LAMBDAS, parallax))
    info = info_of(capsys, path)
    assert info["picture"] == ["focus stack", "depth lookup table", "perspective views"]
    assert [i["lambda"] for i in info["focus_stack"]["images"]] == list(STACK_LAMBDAS)
    assert info["focus_stack"]["images"][0]["representation"] == "h264"
    status, _, err = cli(capsys, "export", path, "-o", tmp_path / "out", "--tiff")
    assert status == 0, err
    scene = lytropics.focus_scene(len(STACK_LAMBDAS), 32)
    for k, lam in enumerate(STACK_LAMBDAS):
        sidecar = json.loads((tmp_path / "out" / f"IMG_0009-stk_stack_{k:02d}.json").read_text())
        assert sidecar["lambda"] == lam and sidecar["index"] == k and "distance_mm" in sidecar
        assert "H.264" in sidecar["encoding"]
        np.testing.assert_allclose(read_image(tmp_path / "out" / f"IMG_0009-stk_stack_{k:02d}.tif"),
                                   srgb_decode(scene[k] / 255.0), atol=0.02)   # I_PCM: YCbCr 8-bit round trip
        assert (tmp_path / "out" / f"IMG_0009-stk_stack_{k:02d}.jpg").read_bytes()[:2] == b"\xff\xd8"
    for k, (rgb, x, y) in enumerate(parallax):
        assert json.loads((tmp_path / "out" / f"IMG_0009-stk_parallax_{k:02d}.json").read_text())["coord"] == [x, y]
    status, _, err = cli(capsys, "viewer", path, "-o", tmp_path / "v")
    assert status == 0, err
    assert len(list((tmp_path / "v" / "stack").glob("*.jpg"))) == len(STACK_LAMBDAS)


# ----------------------------------------------------------------------------- the camera given to export

def _f01_camera_file(tmp_path, **kwargs):
    from lfproc.io._lytro_camera import lytro_camera
    from lfproc.io._lytro_metadata import parse_metadata

    built = lytro_camera(parse_metadata(lytrogen.fixture("f01-frame.json"), None, "f01"), **kwargs)
    path = tmp_path / "f01.toml"
    path.write_text(built.to_toml())
    return path, built.camera


@pytest.mark.parametrize("focus", [None, 500.0])
def test_export_camera_file_for_a_picture_without_metadata(tmp_path, capsys, focus):
    from lfproc.camera import image_distance_for_focus

    pic = lytropics.write(tmp_path / "IMG-stk.lfp", lytropics.first_gen_stack(with_metadata=False))
    cam_path, cam = _f01_camera_file(tmp_path, focus_distance_mm=300.0)
    extra = [] if focus is None else ["--focus-distance", focus]
    status, _, err = cli(capsys, "export", pic, "--camera", cam_path, *extra, "-o", tmp_path / "out")
    assert status == 0, err
    f_u, n, p_m, f_s = cam.main_optics.focal_length_mm, cam.main_optics.f_number, cam.mla_pitch_mm, cam.mla_focal_length_mm
    b_u = cam.main_optics.image_distance_mm if focus is None else image_distance_for_focus(f_u, focus, f_s, "test")
    for k, lam in enumerate((-8.92, -5.78, -2.6)):
        sidecar = json.loads((tmp_path / "out" / f"IMG-stk_stack_{k:02d}.json").read_text())
        assert sidecar["distance_mm"] == pytest.approx(newton_distance(lam, f_u=f_u, n=n, p_m=p_m, f_s=f_s, b_u=b_u),
                                                       rel=1e-9)
        assert sidecar["camera"]["from"] == f"camera file {cam_path}" and "camera_note" not in sidecar
        assert sidecar["provenance"]["inputs"]["camera"]["path"] == str(cam_path)
    record = json.loads((tmp_path / "out" / "IMG-stk_stack_00.json").read_text())["camera"]
    assert record["focus_distance_mm"] == pytest.approx(300.0 if focus is None else focus, rel=1e-9)
    assert (tmp_path / "out" / "IMG-stk_depth.tif").exists()


def test_export_focus_distance_needs_a_camera(tmp_path, capsys):
    pic = lytropics.write(tmp_path / "IMG-stk.lfp", lytropics.first_gen_stack(with_metadata=False))
    ok = lytropics.write(tmp_path / "OK.LFP", lytropics.illum_picture())
    status, _, err = cli(capsys, "export", ok, pic, "--focus-distance", 500, "-o", tmp_path / "out")
    assert status == 2 and len(err) == 1 and str(pic) in err[0] and "--camera" in err[0]
    assert not (tmp_path / "out").exists()
    scope = tmp_path / "scope.toml"
    scope.write_text('[sensor]\npixel_pitch_mm = 0.0065\n[mla]\npitch_mm = 0.125\nfocal_length_mm = 2.5\n'
                     '[microscope]\nobjective_magnification = 20\nnumerical_aperture = 0.5\nimmersion_index = 1.33\n'
                     'tube_lens_focal_length_mm = 200\n')
    status, _, err = cli(capsys, "export", pic, "--camera", scope, "-o", tmp_path / "out")
    assert status == 2 and len(err) == 1 and "objective, not a Lytro camera" in err[0] and not (tmp_path / "out").exists()


def test_export_focus_distance_overrides_the_lambda_reading(tmp_path, capsys):
    pic = lytropics.write(tmp_path / "I.LFP", lytropics.illum_picture())
    status, _, err = cli(capsys, "export", pic, "--focus-distance", 1234.5, "-o", tmp_path / "out")
    assert status == 0, err
    sidecar = json.loads((tmp_path / "out" / "I_stack_03.json").read_text())   # lambda 0: where the lens focused
    assert sidecar["lambda"] == 0.0 and sidecar["distance_mm"] == pytest.approx(1234.5, rel=1e-9)
    assert sidecar["camera"]["image_distance_from"].startswith("--focus-distance")


# ----------------------------------------------------------------------------- views, previews, viewer

def test_views_as_jpeg_and_a_wobble_gif(tmp_path, capsys):
    from PIL import Image

    from lfproc.io import read_metadata

    parallax = views(4)
    pic = lytropics.write(tmp_path / "P-stk.lfp", lytropics.first_gen_stack(parallax=parallax))
    status, _, err = cli(capsys, "export", pic, "--views-jpeg", "--wobble", "-o", tmp_path / "out")
    assert status == 0, err
    for k, (rgb, x, y) in enumerate(parallax):
        jpg = tmp_path / "out" / f"P-stk_parallax_{k:02d}.jpg"
        sidecar = json.loads((tmp_path / "out" / f"P-stk_parallax_{k:02d}.json").read_text())
        assert read_metadata(jpg) == sidecar and sidecar["coord"] == [x, y]
        decoded = np.asarray(Image.open(jpg).convert("RGB"), float)
        np.testing.assert_allclose(decoded.mean(axis=(0, 1)), rgb[0, 0], atol=4)
    gif = Image.open(tmp_path / "out" / "P-stk_wobble.gif")
    assert gif.n_frames == 4
    angles = [math.atan2(y, x) for _, x, y in parallax]
    expected = sorted(range(4), key=lambda k: angles[k])           # around the aperture, by angle
    for frame, k in enumerate(expected):
        gif.seek(frame)
        shown = np.asarray(gif.convert("RGB"), float).mean(axis=(0, 1))
        np.testing.assert_allclose(shown, parallax[k][0][0, 0], atol=8)
    info = info_of(capsys, tmp_path / "out" / "P-stk_wobble.gif")
    assert info["raw_light_field"] is False


def test_depth_preview_in_lambda_without_a_camera(tmp_path, capsys):
    pic = lytropics.write(tmp_path / "N-stk.lfp", lytropics.first_gen_stack(with_metadata=False))
    status, _, err = cli(capsys, "export", pic, "-o", tmp_path / "out")
    assert status == 0, err
    preview = tmp_path / "out" / "N-stk_depth_lambda_preview.png"
    info = info_of(capsys, preview)
    assert info["format"] == "lfproc-output" and info["tags"]["legend"] == "lambda"
    from PIL import Image
    body = np.asarray(Image.open(preview).convert("RGB"), float)[10:400, :400]
    # enlarged smoothly, not in 20 x 20 blocks: far more distinct colours than lookup-table cells
    assert len(np.unique(body.reshape(-1, 3), axis=0)) > 400
    sidecar = json.loads((tmp_path / "out" / "N-stk_stack_00.json").read_text())
    assert "--camera" in sidecar["camera_note"]


def test_viewer_page_for_a_picture_of_perspective_views_only(tmp_path, capsys):
    import base64

    parallax = views(37, size=(16, 16))
    pic = lytropics.write(tmp_path / "V.lfp", lytropics.parallax_only(parallax))
    status, _, err = cli(capsys, "viewer", pic, "-o", tmp_path / "v")
    assert status == 0, err
    text = (tmp_path / "v" / "index.html").read_text()
    start = text.index('id="lfproc-data">') + len('id="lfproc-data">')
    data = json.loads(text[start:text.index("</script>", start)])
    assert len(data["images"]) == 37 and all((tmp_path / "v" / i["image"]).exists() for i in data["images"])
    choice = np.frombuffer(base64.b64decode(data["choice"]["base64"]), np.uint8).reshape(data["choice"]["shape"])
    xs = np.array([x for _, x, _ in parallax])
    ys = np.array([y for _, _, y in parallax])
    rows, cols = choice.shape
    assert xs[choice[rows // 2, 0]] == xs.min() and xs[choice[rows // 2, -1]] == xs.max()   # left edge: leftmost
    assert ys[choice[0, cols // 2]] == ys.min() and ys[choice[-1, cols // 2]] == ys.max()


# ----------------------------------------------------------------------------- exported images are pictures

def test_exported_images_are_recognised_not_raw_light_fields(tmp_path, capsys, paper_camera):
    from conftest import assert_clean_error, run_cli

    pic = lytropics.write(tmp_path / "X-stk.lfp", lytropics.first_gen_stack(with_metadata=False))
    status, _, err = cli(capsys, "export", pic, "-o", tmp_path / "out")
    assert status == 0, err
    jpg = tmp_path / "out" / "X-stk_stack_00.jpg"
    info = info_of(capsys, jpg)
    assert info["raw_light_field"] is False and info["format"] == "lfproc-output"
    assert "Lytro picture" in info["product"]
    # embedded tags stripped by another program: the sidecar beside it still tells
    plain = tmp_path / "out" / "plain.jpg"
    plain.write_bytes(lytropics.jpeg(lytropics.focus_scene(3)[0]))
    (tmp_path / "out" / "plain.json").write_text((tmp_path / "out" / "X-stk_stack_00.json").read_text())
    assert info_of(capsys, plain)["raw_light_field"] is False
    white = tmp_path / "white.png"
    from PIL import Image
    Image.fromarray(np.full((48, 48), 200, np.uint8)).save(white)
    proc = run_cli("refocus", jpg, "--camera", paper_camera, "--white", white, "--a", "0", "-o", tmp_path / "r")
    assert_clean_error(proc, str(jpg), "no raw light field")
    assert not (tmp_path / "r").exists()


# ----------------------------------------------------------------------------- raw image removed

def test_container_whose_raw_image_was_removed_still_describes_the_camera(tmp_path, capsys):
    from lfproc import Camera

    meta = json.dumps(lytrogen.f01_metadata(3280, 3280)).encode()
    private = json.dumps({"camera": {"serialNumber": "A202110453"}}).encode()
    toc = {"picture": {"frameArray": [{"frame": {"metadataRef": lytrogen.sha1_ref(meta),
                                                 "privateMetadataRef": lytrogen.sha1_ref(private),
                                                 "imageRef": lytropics.RAW_REF}}],
                       "viewArray": [], "accelerationArray": []}}
    path = lytropics.write(tmp_path / "Lytro.lfp", lytropics.assemble(toc, [meta, private]))
    info = info_of(capsys, path)
    assert info["raw_light_field"] is False and info["raw_frame"].startswith("missing")
    assert (info["camera_model"], info["serial"], info["width"], info["cfa"]) == ("F01", "A202110453", 3280, "BGGR")
    status, _, err = cli(capsys, "camera", path, "-o", tmp_path / "c.toml")
    assert status == 0, err
    assert Camera.from_toml(tmp_path / "c.toml").mla_focal_length_mm == 0.025


# ----------------------------------------------------------------------------- napari-LF metadata

def test_napari_metadata_gives_a_microscope_camera_file(tmp_path, capsys):
    from lfproc import Camera

    settings = {"calibrate": {"ulens_pitch": 150.0, "pixel_size": 6.5, "ulens_focal_length": 3000.0,
                              "ulens_focal_distance": 2900.0, "objective_magnification": 40, "objective_na": 0.8,
                              "tubelens_focal_length": 180.0, "center_wavelength": 520.0, "medium_index": 1.33}}
    (tmp_path / "rig40").mkdir()
    meta = tmp_path / "rig40" / "metadata.txt"
    meta.write_text(json.dumps(settings))
    out = tmp_path / "lfm.toml"
    status, _, err = cli(capsys, "camera", meta, "-o", out)
    assert status == 0, err
    cam = Camera.from_toml(out)
    scope = cam.main_optics
    assert (cam.pixel_pitch_mm, cam.mla_pitch_mm, cam.mla_focal_length_mm) == (0.0065, 0.15, 2.9)
    assert (scope.objective_magnification, scope.numerical_aperture, scope.immersion_index) == (40, 0.8, 1.33)
    assert (scope.tube_lens_focal_length_mm, scope.relay_magnification, scope.wavelength_nm) == (180, 1, 520)
    assert cam.grid == "rectangular" and cam.name == "rig40 (napari-LF)"
    provenance = tomllib.loads(out.read_text())["provenance"]
    assert provenance["mla.focal_length_mm"] == "napari-LF metadata: calibrate.ulens_focal_distance (um)"
    assert "no relay" in provenance["microscope.relay_magnification"]
    del settings["calibrate"]["objective_na"]
    meta.write_text(json.dumps(settings))
    status, _, err = cli(capsys, "camera", meta, "-o", tmp_path / "x.toml")
    assert status == 2 and len(err) == 1 and "objective_na" in err[0] and not (tmp_path / "x.toml").exists()


def test_export_camera_file_overrides_the_pictures_metadata(tmp_path, capsys):
    """An Illum picture exported with an F01 camera file: the camera file's optics apply, and say so."""
    pic = lytropics.write(tmp_path / "I.LFP", lytropics.illum_picture())
    cam_path, cam = _f01_camera_file(tmp_path, focus_distance_mm=800.0)
    status, _, err = cli(capsys, "export", pic, "--camera", cam_path, "-o", tmp_path / "out")
    assert status == 0, err
    sidecar = json.loads((tmp_path / "out" / "I_stack_00.json").read_text())
    assert sidecar["camera_model"] == "B01" and sidecar["camera"]["from"] == f"camera file {cam_path}"
    assert sidecar["camera"]["f_number"] == cam.main_optics.f_number and sidecar["camera"]["focus_distance_mm"] == pytest.approx(800)
    expected = newton_distance(-15.0, f_u=cam.main_optics.focal_length_mm, n=cam.main_optics.f_number, p_m=cam.mla_pitch_mm,
                               f_s=cam.mla_focal_length_mm, b_u=cam.main_optics.image_distance_mm)
    assert sidecar["lambda"] == -15.0 and sidecar["distance_mm"] == pytest.approx(expected, rel=1e-9)
