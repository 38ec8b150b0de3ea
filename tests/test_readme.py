"""The README's two set-up commands are the ones CI runs, the demo prints what the README shows, and every
block of "Your own data" runs as written: on the bundled sample (the command line and Python writing the same
files), the bundled Lytro file and a rendered light-field microscope (tests/real/test_real_readme.py walks the
microscope block on the real sea urchin)."""

import json
import re

import numpy as np
import pytest

from conftest import ROOT, run_cli
from readme_walk import (README, blocks, own_data_section, run_commands, run_python, same_outputs,
                         same_volume, volume_written)

CI = (ROOT / ".ci" / "run").read_text()


def test_ci_runs_the_readme_test_command():
    ci_lines = [line for line in CI.splitlines() if "pytest" in line and not line.startswith("#")]
    assert len(ci_lines) == 1
    assert ci_lines[0].strip() in README


def test_readme_first_screen_has_both_commands():
    first_screen = "\n".join(README.splitlines()[:40])
    assert re.search(r"^python3 -m venv .*lfproc demo$", first_screen, re.M)
    assert re.search(r"^python3 -m venv .*pytest.*$", first_screen, re.M)


def test_the_readme_is_short_and_states_no_dated_number():
    assert len(README.splitlines()) <= 250
    assert not re.search(r"20\d\d-\d\d-\d\d", README)                     # dates and the timings they date
    assert "<!--n:" not in README and "<!--p:" not in README               # measurements live in docs/


def test_the_demo_prints_what_the_readme_shows(tmp_path):
    shown = blocks(README[README.index("## Set-up"):README.index("## Your own data")], "text")[0].splitlines()
    proc = run_cli("demo", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    printed = proc.stdout.splitlines()
    assert len(printed) == len(shown)
    for ours, theirs in zip(printed, shown):
        if theirs.startswith("viewer: "):
            assert ours.startswith("viewer: ") and ours.endswith("lfproc-demo/viewer/index.html")
        elif theirs.startswith("done in"):
            assert re.sub(r"done in [\d.]+ s", "done in … s", ours) == theirs
        else:
            assert ours == theirs


def test_the_commands_table_lists_every_command():
    from lfproc.cli import COMMANDS

    table = README[README.index("## Commands"):README.index("`INPUT` is a capture")]
    assert re.findall(r"^\| `lfproc (\w+)", table, re.M) == list(COMMANDS)


def test_the_camera_file_is_the_paper_camera():
    from lfproc import Camera

    toml = next(block for block in blocks(own_data_section("A camera of your own"), "toml"))
    assert Camera.from_toml_string(toml) == Camera.from_toml(ROOT / "samples" / "cameras" / "paper-f100.toml")


def _folder_with_samples(path):
    path.mkdir()
    (path / "samples").symlink_to(ROOT / "samples")
    return path


def test_your_own_camera_on_the_command_line_and_in_python_writes_the_same_files(tmp_path):
    section = own_data_section("A camera of your own")
    cli, python = _folder_with_samples(tmp_path / "cli"), _folder_with_samples(tmp_path / "python")
    procs = run_commands(section, cli)
    namespace = run_python(section, python)
    assert same_outputs(cli / "out", python / "out", ["grid.json", "slices", "views", "depth"]) > 10
    # the geometry with the grid gives the slices' own numbers, as the sidecars
    geometry = procs[-1].stdout
    for record in namespace["slices"].records():
        assert f"{record['distance_mm']:.3f}" in geometry, (record["distance_mm"], geometry)
    assert namespace["slices"].images.shape[0] == 2
    assert json.loads((cli / "out" / "grid.json").read_text())["made_from"]


def test_a_lytro_picture_as_the_readme_says(tmp_path):
    section = own_data_section("A Lytro picture")
    folder = _folder_with_samples(tmp_path / "lytro")
    run_commands(section, folder)
    written = sorted((folder / "out" / "lytro-slices").glob("IMG_0001_*"))
    assert {p.suffix for p in written} == {".tif", ".json"} and len(written) >= 2
    assert all(json.loads(p.read_text())["distance_mm"] > 0 for p in written if p.suffix == ".json")
    namespace = run_python(section, folder)
    distances = [r["distance_mm"] for r in namespace["lytro_slices"].records()]
    assert distances == pytest.approx([10000.0, 30000.0], rel=1e-9)


#: napari-LF's "calibrate" table for the rendered microscope (the keys of its metadata.txt; µm, mm for the tube)
RENDERED_SCOPE = {"pixel_size": 13.0, "ulens_pitch": 125, "ulens_focal_length": 2433, "ulens_focal_distance": 2433,
                  "objective_magnification": 20, "objective_na": 0.5, "tubelens_focal_length": 200.0,
                  "center_wavelength": 510, "medium_index": 1.33}


def write_rendered_scope(folder):
    """A microscope folder as the README names it: napari-LF's metadata.txt, white, dark and a capture of two
    beads and a sheet, rendered by lfproc's ray-traced microscope simulator with a dark offset."""
    import tifffile

    import lfproc
    from lfproc.simulate import Bead, MicroscopeScene, Sheet, render_microscope_sensor

    folder.mkdir()
    (folder / "metadata.txt").write_text(json.dumps({"calibrate": RENDERED_SCOPE, "rectify": {}}))
    camera = lfproc.read_camera(folder / "metadata.txt")
    scene = MicroscopeScene(beads=(Bead(-30.0, 20.0, -20.0), Bead(25.0, -30.0, 20.0)),
                            sheets=(Sheet(z_um=0.0, period_um=40.0),))
    white = render_microscope_sensor(camera, None, (231, 231))
    light = render_microscope_sensor(camera, scene, (231, 231))
    rng = np.random.default_rng(5)
    dark = 500.0 + rng.normal(0.0, 3.0, white.shape)
    for name, image in (("white.tif", 500.0 + white / white.max() * 50000), ("dark.tif", dark),
                        ("capture.tif", 500.0 + rng.poisson(light / light.max() * 20000))):
        tifffile.imwrite(folder / name, np.round(image).astype(np.uint16))
    return folder


def test_a_microscope_as_the_readme_says(tmp_path):
    section = own_data_section("A light-field microscope")
    scope = write_rendered_scope(tmp_path / "scope")
    (tmp_path / "samples").symlink_to(ROOT / "samples")
    run_commands(section, tmp_path)
    volume_file = tmp_path / "beads" / "volume" / "capture_volume.ome.tif"
    assert volume_file.is_file()                                          # the bead render, deconvolved
    by_command = volume_written(scope / "volume")                        # before Python writes over it
    stack_record = json.loads(next((scope / "stack").glob("*_z-40.000um.json")).read_text())
    namespace = run_python(section, tmp_path)
    stack, volume = namespace["z_stack"], namespace["volume"]
    assert list(stack.z_um) == [-40.0, -30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0, 40.0]
    assert stack.records()[0]["z_um"] == stack_record["z_um"] and stack.records()[0]["dof_um"] == stack_record["dof_um"]
    same_volume(volume, by_command)


def _anchor(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def test_every_relative_link_of_the_readme_and_docs_reaches_its_file_and_heading():
    broken = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = page.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)\s]+)\)", re.sub(r"```.*?```", "", text, flags=re.S)):
            if re.match(r"[a-z]+:", target) or not ("." in target or target.startswith("#")):
                continue                                      # a web address, or maths such as x[k](j)
            path, _, anchor = target.partition("#")
            linked = (page.parent / path).resolve() if path else page
            if not linked.exists():
                broken.append(f"{page.name}: {target}")
            elif anchor and linked.suffix == ".md":
                headings = re.findall(r"^#+ (.*)$", re.sub(r"```.*?```", "", linked.read_text(encoding="utf-8"),
                                                              flags=re.S), re.M)
                if anchor not in {_anchor(h) for h in headings}:
                    broken.append(f"{page.name}: {target} (no such heading)")
    assert not broken, "\n".join(broken)


def test_the_readmes_other_numbers_are_the_codes():
    """The sample's planes, the Python it needs and the deconvolution's default iterations, as the README says."""
    import inspect

    import lfproc

    truth = json.loads((ROOT / "samples" / "sample" / "ground_truth.json").read_text())
    planes = sorted(round(p["distance_mm"]) for p in truth["planes"])
    assert f"three textured planes at {planes[0]}, {planes[1]} and {planes[2]} mm" in README
    python = re.search(r'^requires-python = ">=(3\.\d+)"$', (ROOT / "pyproject.toml").read_text(), re.M).group(1)
    assert f"Only Python ≥ {python} is needed" in README
    iterations = inspect.signature(lfproc.deconvolve).parameters["iterations"].default
    assert f"# Richardson–Lucy, {iterations} iterations" in README
