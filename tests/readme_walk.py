"""Walking the README's "Your own data" blocks: each section's commands and its Python, as written.

Shared by tests/test_readme.py (the sample, the bundled Lytro file, a rendered microscope) and
tests/real/test_real_readme.py (the real sea urchin, where present).
"""

from __future__ import annotations

import json
import os
import re
import shlex
from pathlib import Path

import numpy as np

from conftest import ROOT, run_cli

README = (ROOT / "README.md").read_text(encoding="utf-8")


def own_data_section(title: str) -> str:
    """The text of the "### TITLE" subsection of "## Your own data"."""
    part = README[README.index("## Your own data"):]
    part = part[:part.index("\n## ", 3)]
    start = part.index(f"### {title}")
    end = part.find("\n### ", start + 4)
    return part[start:] if end < 0 else part[start:end]


def blocks(section: str, language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", section, re.S)


def commands(section: str) -> list[list[str]]:
    """Each ``lfproc …`` line of the section's sh blocks (continuations joined), without ``lfproc``."""
    found = []
    for block in blocks(section, "sh"):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words:
                assert words[0] == "lfproc", line
                found.append(words[1:])
    return found


def run_commands(section: str, folder: Path, extra: dict[str, list[str]] | None = None) -> list:
    """Runs the section's commands in ``folder`` (each must succeed); ``extra`` appends options to a
    command by its name (e.g. fewer iterations on a large real capture)."""
    done = []
    for args in commands(section):
        args = args + (extra or {}).get(args[0], [])
        proc = run_cli(*args, cwd=folder)
        assert proc.returncode == 0, (args, proc.stderr)
        done.append(proc)
    return done


def run_python(section: str, folder: Path, replace: dict[str, str] | None = None) -> dict:
    """Execs the section's Python blocks, in order, in one namespace, in ``folder``."""
    namespace: dict = {}
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        for code in blocks(section, "python"):
            if "import lfproc" not in code:
                code = "import lfproc\n" + code
            for old, new in (replace or {}).items():
                code = code.replace(old, new)
            exec(compile(code, "README.md", "exec"), namespace)
    finally:
        os.chdir(cwd)
    return namespace


def same_outputs(a: Path, b: Path, folders) -> int:
    """Every sidecar and image the two runs wrote under each of ``folders`` is the same (JSON equal but for the
    runs' own folders in absolute paths, images equal in float32, NaN where unknown); returns how many files
    were compared."""
    import tifffile

    compared = 0
    for name in folders:
        left, right = ([Path(name)] if (root / name).is_file() else
                       sorted(p.relative_to(root) for p in (root / name).rglob("*") if p.is_file()) for root in (a, b))
        assert left == right and left, (name, left, right)
        for path in left:
            if path.suffix == ".json":
                assert _sidecar(a / path, a.parent) == _sidecar(b / path, b.parent), path
            elif path.suffix in (".tif", ".tiff") and not path.name.endswith(".ome.tif"):
                np.testing.assert_array_equal(tifffile.imread(a / path), tifffile.imread(b / path), err_msg=str(path))
            compared += 1
    return compared


def _sidecar(path: Path, folder: Path):
    """The JSON with the run's folder in absolute paths written HERE, and without the grid file's SHA-256 (the
    grid files hold those paths; same_outputs compares them)."""
    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if not (k == "sha256" and value.get("path", "").endswith(
                "grid.json"))}
        return [strip(v) for v in value] if isinstance(value, list) else value
    return strip(json.loads(path.read_text().replace(str(folder), "HERE")))


def volume_written(folder):
    """(record, data) of the one volume ``lfproc deconvolve`` wrote in ``folder``."""
    import tifffile

    return (json.loads(next(folder.glob("*_volume.json")).read_text()),
            tifffile.imread(next(folder.glob("*_volume.ome.tif"))))


def same_volume(volume, written, rtol=1e-5):
    """The Python volume is the command's: the same planes, voxel size, iterations and voxels (float32)."""
    record, data = written
    assert record["z_um"] == list(volume.z_um) and record["voxel_um"] == list(volume.voxel_um)
    assert record["iterations"] == volume.records()["iterations"] and np.isfinite(volume.data).all()
    np.testing.assert_allclose(volume.data, data, rtol=rtol, atol=rtol * float(np.abs(data).max()))
