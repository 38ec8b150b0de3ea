"""``lfproc info`` on lfproc's own pictures: previews (PNG/JPEG), the labelled mosaic preview, depth previews and
focal z-stacks (ImageJ, OME-TIFF) are told for what they are, never as raw light fields; foreign files as before."""

import json

import numpy as np
import pytest
import tifffile

from lfproc import Camera, LightField
from lfproc.io import describe_file
from lfproc.camera import NATIVE_PLANE_UM
from lfproc.outputs import write_focal_stack

from conftest import SAMPLES, assert_clean_error, run_cli

SAMPLE = SAMPLES / "sample"


@pytest.fixture(scope="module")
def small_lf(tmp_path_factory):
    """An 11x11-view light field of random texture with the sample's camera (small: the commands take a second)."""
    views = np.random.default_rng(3).random((11, 11, 24, 32, 3)).astype(np.float32)
    path = tmp_path_factory.mktemp("info") / "small.lfp.npz"
    LightField.from_views(views, Camera.from_toml(SAMPLE / "camera.toml")).save(path)
    return path


def info_json(path):
    proc = run_cli("info", path, "--json")
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_refocus_previews_are_preview_pictures_with_their_tags(small_lf, tmp_path):
    proc = run_cli("refocus", small_lf, "--a", "0.5", "--preview", "-o", tmp_path / "png")
    assert proc.returncode == 0, proc.stderr
    proc = run_cli("refocus", small_lf, "--a", "0.5", "--preview", "--preview-format", "jpeg", "-o", tmp_path / "jpg")
    assert proc.returncode == 0, proc.stderr
    sidecar = json.loads((tmp_path / "png" / "small_00_a+0.500.json").read_text())
    for path in (tmp_path / "png" / "small_00_a+0.500_preview.png", tmp_path / "jpg" / "small_00_a+0.500_preview.jpg"):
        info = info_json(path)
        assert info["format"] == "lfproc-output" and info["raw_light_field"] is False, info
        assert info["product"] == "preview picture" and info["preview_of"] == "refocused slice"
        assert info["tags"]["a"] == sidecar["a"] == 0.5
        metres = f"{sidecar['distance_mm'] / 1000:.3g} m"
        assert info["tags"]["label"].startswith(f"focus {metres}"), info["tags"]   # the label drawn on it
        text = run_cli("info", path).stdout
        assert "preview picture" in text and "refocused slice" in text and "raw_light_field        False" in text


def test_view_and_mosaic_previews_say_which_views(small_lf, tmp_path):
    proc = run_cli("views", small_lf, "--mosaic", "--preview", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    view = info_json(tmp_path / "small_view_01_03_preview.png")
    assert view["product"] == "preview picture" and view["preview_of"] == "view"
    assert view["tags"]["view"] == [1, 3] and view["raw_light_field"] is False
    mosaic = info_json(tmp_path / "small_views_mosaic_preview.png")
    assert mosaic["preview_of"] == "view mosaic" and mosaic["raw_light_field"] is False
    assert mosaic["tags"]["views_shown"] == 121 and mosaic["tags"]["views_per_side"] == 11
    assert mosaic["tags"]["label"].startswith("121 of 11x11 views")


def test_animations_are_preview_pictures(small_lf, tmp_path):
    proc = run_cli("views", small_lf, "--gif", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    info = info_json(tmp_path / "small_views.gif")
    assert info["product"] == "preview picture" and info["preview_of"] == "view animation"
    assert info["raw_light_field"] is False and info["tags"]["views_per_side"] == 11
    from lfproc.outputs import write_slice_gif

    stack = np.random.default_rng(4).random((3, 12, 16, 1)).astype(np.float32)
    camera = Camera.from_toml(SAMPLE / "camera.toml")
    path = write_slice_gif(str(tmp_path), "s", stack, camera, [1.0, 0.5, 0.0])
    info = describe_file(path)
    assert info["preview_of"] == "refocus animation" and info["tags"]["a"] == [1.0, 0.5, 0.0]
    assert info["tags"]["frames"] == 3 and "software" not in info["tags"]


def test_an_animation_from_a_long_path_is_still_a_preview_picture(tmp_path):
    """Its tags name the source: past 255 bytes the GIF comment takes several blocks, all of them read."""
    from lfproc.io import write_gif_frames

    source = str(tmp_path / ("deep" * 70) / "capture.png")
    frames = [np.full((8, 8, 3), value, np.uint8) for value in (0, 255)]
    path = write_gif_frames(tmp_path / "long.gif", frames, 100.0, {"preview": "view animation", "source": source})
    info = describe_file(path)
    assert info["product"] == "preview picture" and info["raw_light_field"] is False
    assert info["tags"] == {"preview": "view animation", "source": source}


def test_depth_preview_is_a_preview_picture(tmp_path):
    from lfproc.depth._preview import write_preview

    distance = np.linspace(500.0, 2000.0, 12 * 16).reshape(12, 16)
    write_preview(str(tmp_path / "d_depth_preview.png"), distance)
    info = describe_file(tmp_path / "d_depth_preview.png")
    assert info["product"] == "preview picture" and info["preview_of"] == "depth map"
    assert info["raw_light_field"] is False


def microscope_records(z_values):
    return [{"source": "x.png", "a": z / 10.0, "z_um": z, "z_near_um": z - 1, "z_far_um": z + 1, "dof_um": 2.0}
            for z in z_values]


@pytest.mark.parametrize("kind,name,unit", [("imagej", "s_stack.tif", "micron"), ("ome", "s_stack.ome.tif", "µm")])
def test_microscope_stack_is_a_z_stack_with_its_spacing(tmp_path, kind, name, unit):
    z = [-3.0, -1.5, 0.0, 1.5]
    images = np.random.default_rng(0).random((4, 6, 7, 3)).astype(np.float32)
    path = write_focal_stack(str(tmp_path / name), images, microscope_records(z), NATIVE_PLANE_UM, kind=kind, lens_um=6.25,
                             upsample=2)
    info = info_json(path)
    assert info["format"] == "lfproc-output" and info["raw_light_field"] is False
    assert info["product"] == "focal stack (z-stack)" and info["stack_format"] == kind
    assert (info["width"], info["height"], info["channels"], info["slices"]) == (7, 6, 3, 4)
    assert info["spacing"] == pytest.approx({"x": 3.125, "y": 3.125, "z": 1.5, "unit": unit})
    assert [s["z_um"] for s in info["tags"]["slices"]] == z and info["tags"]["z_spacing_um"] == 1.5
    text = run_cli("info", path).stdout
    assert "focal stack (z-stack)" in text and "slices (4):" in text and "z 1.5" in text
    assert "z_um -1.5" in text
    # a cut stack: no log lines from the TIFF library, described as far as its header goes
    (tmp_path / "cut.tif").write_bytes(open(path, "rb").read()[:2000])
    cut = run_cli("info", tmp_path / "cut.tif")
    assert cut.returncode == 0 and cut.stderr == "", cut.stderr
    # a z-stack is no capture: refused with one line where a capture is read
    assert_clean_error(run_cli("decode", path, "--camera", SAMPLES / "cameras" / "lfm-20x.toml", "--white",
                               path, "-o", tmp_path / "x.lfp.npz"), "no raw light field")


def test_photographic_stack_from_refocus_is_a_z_stack(small_lf, tmp_path):
    proc = run_cli("refocus", small_lf, "--a", "0,0.5,1", "--stack", "imagej", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    info = info_json(tmp_path / "small_stack.tif")
    assert info["product"] == "focal stack (z-stack)" and info["slices"] == 3
    assert info["spacing"]["unit"] == "pixel"
    assert [s["a"] for s in info["tags"]["slices"]] == [0.0, 0.5, 1.0]


def test_foreign_pictures_are_described_as_before(tmp_path):
    from PIL import Image, PngImagePlugin

    pixels = np.random.default_rng(1).integers(0, 255, (9, 11, 3), dtype=np.uint8)
    Image.fromarray(pixels).save(tmp_path / "plain.png")
    tagged = PngImagePlugin.PngInfo()
    tagged.add_text("Software", "GIMP")
    tagged.add_text("Description", json.dumps({"preview": "refocused slice"}))
    Image.fromarray(pixels).save(tmp_path / "gimp.png", pnginfo=tagged)
    Image.fromarray(pixels).save(tmp_path / "commented.gif", comment=json.dumps({"preview": "view animation"}))
    for name in ("plain.png", "gimp.png", "commented.gif"):
        info = info_json(tmp_path / name)
        assert info["format"] == "image" and info["raw_light_field"] is True, info
        assert (info["width"], info["height"]) == (11, 9) and "product" not in info
    # ImageJ and OME TIFFs lfproc did not write are plain images
    stack = np.zeros((3, 9, 11), np.float32)
    tifffile.imwrite(tmp_path / "fiji.tif", stack, imagej=True, metadata={"axes": "ZYX", "spacing": 2.0})
    tifffile.imwrite(tmp_path / "bf.ome.tif", stack, ome=True, metadata={"axes": "ZYX"})
    for name in ("fiji.tif", "bf.ome.tif"):
        info = info_json(tmp_path / name)
        assert info["format"] == "image" and info["raw_light_field"] is True, info
