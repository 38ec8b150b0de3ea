"""What a newcomer meets first: display-ready previews, honest view outputs, the bundled samples, help texts
that point at documentation a wheel install has, and ``lfproc info`` on lfproc's own outputs."""

import json
import re

import numpy as np
import pytest

import lfproc
from conftest import SAMPLES, assert_clean_error, run_cli

SAMPLE = SAMPLES / "sample"


def _read(path):
    import OpenImageIO as oiio

    return oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)


def test_views_writes_only_views_with_light(sample_lf, tmp_path):
    lf = lfproc.LightField.load(sample_lf)
    assert lf.view_mask is not None, "the sample's decoding drops views: this test needs some dark ones"
    proc = run_cli("views", sample_lf, "-o", tmp_path, "--mosaic")
    assert proc.returncode == 0, proc.stderr
    written = sorted(tmp_path.glob("sample_view_*.tif"))
    assert len(written) == int(lf.view_mask.sum())
    for path in written:
        ky, kx = map(int, re.findall(r"_(\d+)_(\d+)\.tif$", path.name)[0])
        assert lf.view_mask[ky, kx]
        assert _read(path).max() > 0, f"{path.name} is written but black"
    dark = int((~lf.view_mask).sum())
    assert f"{len(written)} of {lf.view_mask.size} views written ({dark} without light)" in proc.stdout


def test_views_mosaic_shows_lit_views_and_has_a_labelled_preview(sample_lf, tmp_path):
    lf = lfproc.LightField.load(sample_lf)
    assert run_cli("views", sample_lf, "-o", tmp_path, "--mosaic").returncode == 0
    sidecar = json.loads((tmp_path / "sample_views_mosaic.json").read_text())
    shown = {tuple(v["view"]) for v in sidecar["views"]}
    assert shown == {tuple(map(int, k)) for k in np.argwhere(lf.view_mask)}
    rows, cols = np.flatnonzero(lf.view_mask.any(1)), np.flatnonzero(lf.view_mask.any(0))
    assert sidecar["first_view"] == [int(rows[0]), int(cols[0])]
    tiled = _read(tmp_path / "sample_views_mosaic.tif")
    ny, nx = lf.lens_shape
    assert tiled.shape[:2] == (len(rows) * ny, len(cols) * nx)     # cropped to the lit rows and columns
    black_blocks = sum(tiled[by * ny:(by + 1) * ny, bx * nx:(bx + 1) * nx].max() == 0
                       for by in range(len(rows)) for bx in range(len(cols)))
    assert black_blocks == len(rows) * len(cols) - len(shown)       # only unlit views inside that range are black
    from PIL import Image
    preview = np.asarray(Image.open(tmp_path / "sample_views_mosaic_preview.png"))
    assert max(preview.shape[:2]) >= 512 and preview.dtype == np.uint8
    band = preview[-12:]
    assert band.max() == 255 and np.median(band) == 0               # a white label on a black band


def test_refocus_preview_and_jpeg_use_the_display_range(sample_lf, tmp_path):
    proc = run_cli("refocus", sample_lf, "--a", "1,2", "--upsample", "2", "--format", "jpeg", "--preview",
                   "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    from PIL import Image
    jpegs = []
    for a in ("00_a+1.000", "01_a+2.000"):
        sidecar = json.loads((tmp_path / f"sample_{a}.json").read_text())
        jpegs.append(np.asarray(Image.open(tmp_path / f"sample_{a}.jpg")))
        assert "tone_map" in sidecar
        preview = np.asarray(Image.open(tmp_path / f"sample_{a}_preview.png"))
        assert preview.shape[1] >= 512 and preview.shape[2] == 3
        assert preview.shape[0] > 512 * jpegs[-1].shape[0] / jpegs[-1].shape[1]   # the image plus its label band
        assert np.median(preview[-10:]) == 0 and preview[-10:].max() == 255
    # one exposure for the stack: its darkest and brightest parts reach the ends of the 8-bit range (a linear
    # JPEG of this scene spans only about 115..225: pale and flat)
    low, high = np.percentile(np.stack(jpegs), [0.5, 99.5])
    assert low < 25 and high > 230, (low, high)
    # a preview in JPEG on request
    assert run_cli("refocus", "--preview", sample_lf, "--a", "1", "--preview-format", "jpeg",
                   "-o", tmp_path / "j").returncode == 0     # --preview before the input: a flag, it takes no value
    assert (tmp_path / "j" / "sample_00_a+1.000_preview.jpg").is_file()


def test_info_shows_the_tags_of_lfproc_outputs(sample_lf, tmp_path):
    assert run_cli("refocus", sample_lf, "--a", "1", "-o", tmp_path).returncode == 0
    proc = run_cli("info", tmp_path / "sample_00_a+1.000.tif", "--json")
    info = json.loads(proc.stdout)
    assert info["format"] == "lfproc-output" and info["raw_light_field"] is False
    assert info["product"] == "refocused slice"
    sidecar = json.loads((tmp_path / "sample_00_a+1.000.json").read_text())
    assert info["tags"] == sidecar
    text = run_cli("info", tmp_path / "sample_00_a+1.000.tif").stdout
    assert "distance_mm" in text and "refocused slice" in text
    # a capture lfproc simulated is still a capture, whatever writer made it
    capture = json.loads(run_cli("info", SAMPLE / "capture.png", "--json").stdout)
    assert capture["format"] == "image" and capture["raw_light_field"] is True


def test_samples_are_found_from_any_install():
    proc = run_cli("info", "--samples", "--json")
    listed = json.loads(proc.stdout)
    for path in listed["samples"].values():
        assert __import__("os").path.exists(path), path
    assert lfproc.sample_path("sample/capture.png").is_file()
    with pytest.raises(lfproc.LfprocError, match=r"lfproc\.sample_path\(\) is their folder"):
        lfproc.sample_path("nope.png")
    text = run_cli("info", "--samples").stdout
    assert str(lfproc.sample_path("sample/white.png")) in text
    assert_clean_error(run_cli("info"), "--samples")


def test_sample_ground_truth_names_only_shipped_files():
    truth = json.loads((SAMPLE / "ground_truth.json").read_text())

    def strings(node):
        if isinstance(node, dict):
            return [s for v in node.values() for s in strings(v)]
        if isinstance(node, list):
            return [s for v in node for s in strings(v)]
        return [node] if isinstance(node, str) else []

    for text in strings(truth):
        for name in re.findall(r"[\w.-]+\.(?:npz|png|toml|json)\b", text):
            assert (SAMPLE / name).exists() or "not shipped" in text, (name, text)


def test_help_texts_point_at_documentation_a_wheel_has():
    from lfproc.cli import COMMANDS

    for command in COMMANDS:
        proc = run_cli(command, "--help")
        assert proc.returncode == 0
        assert not re.search(r"(?<!checkout has more in )docs/\w", proc.stdout), (command, proc.stdout)


def test_geometry_plot_says_where_it_went(tmp_path):
    import matplotlib  # noqa: F401  (a [test] dependency: --plot needs it, and the suite always has it)
    camera = SAMPLES / "cameras" / "paper-f100.toml"
    proc = run_cli("geometry", "--camera", camera, "--plot", tmp_path / "slices.png")
    assert proc.returncode == 0 and str(tmp_path / "slices.png") in proc.stdout
    proc = run_cli("geometry", "--camera", camera, "--json", "--plot", tmp_path / "s2.png")
    json.loads(proc.stdout)                                       # stdout stays one JSON object
    assert str(tmp_path / "s2.png") in proc.stderr and (tmp_path / "s2.png").is_file()


def test_lightfield_load_is_documented():
    assert "Returns" in (lfproc.LightField.load.__doc__ or "")


def test_a_capture_given_as_the_camera_file_is_named_as_such():
    assert_clean_error(run_cli("geometry", "--camera", SAMPLE / "capture.png"), "capture.png", "not a camera file")
