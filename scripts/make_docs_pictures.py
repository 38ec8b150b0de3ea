#!/usr/bin/env python
"""Regenerate every picture the README and docs show, from today's code and the bundled sample.

One entry point anyone can rerun (issue 32); each picture comes from the command a user would run:

- ``docs/depth-sample.png``: ``lfproc depth`` on the bundled sample, its ``capture_depth_preview.png``
  (the colour-mapped depth map with its legend in metres);
- ``docs/refocus-sample.png``: ``lfproc refocus --preview`` on the sample, the slice on the near card,
  enlarged and labelled as every preview is;
- ``docs/viewer.png``: the viewer's screenshot (``scripts/viewer_screenshot.py``: needs Chromium and
  chromedriver; skipped with a note without them);
- ``docs/exit-pupil-error.png`` and ``docs/microscope-geometry.png``: the geometry figures
  (``scripts/exit_pupil_figure.py``, ``scripts/microscope_figure.py``; matplotlib).

``docs/benchmarks.png`` is a measurement, not a picture of an output: ``scripts/bench.py`` makes it.

Usage: ``PYTHONPATH=. python scripts/make_docs_pictures.py [--only NAME ...] [--docs DIR]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "lfproc" / "samples" / "sample"
#: the slice of the refocus picture: the near card (0.38 m in the sample's scene)
REFOCUS_AT_MM = 380


def _lfproc(*args) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    subprocess.run([sys.executable, "-m", "lfproc", *map(str, args)], check=True, cwd=ROOT, env=env,
                   stdout=subprocess.DEVNULL)


def _inputs() -> list:
    return [SAMPLE / "capture.png", "--camera", SAMPLE / "camera.toml", "--white", SAMPLE / "white.png"]


def depth_sample(docs: Path, work: Path) -> Path:
    _lfproc("depth", *_inputs(), "--no-ply", "-o", work / "depth")
    out = docs / "depth-sample.png"
    shutil.copyfile(work / "depth" / "capture_depth_preview.png", out)
    return out


def refocus_sample(docs: Path, work: Path) -> Path:
    _lfproc("refocus", *_inputs(), "--at", REFOCUS_AT_MM, "--preview", "-o", work / "refocus")
    [preview] = sorted((work / "refocus").glob("capture_*_preview.png"))
    out = docs / "refocus-sample.png"
    shutil.copyfile(preview, out)
    return out


def _script(name: str, *args) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    subprocess.run([sys.executable, str(ROOT / "scripts" / name), *map(str, args)], check=True, cwd=ROOT, env=env)


def viewer(docs: Path, work: Path) -> Path | None:
    if not ((shutil.which("chromium") or shutil.which("chromium-browser")) and shutil.which("chromedriver")):
        print("viewer: skipped (needs chromium and chromedriver: apt-get install -y chromium chromium-driver)")
        return None
    out = docs / "viewer.png"
    _script("viewer_screenshot.py", "--out", out)
    return out


def exit_pupil(docs: Path, work: Path) -> Path:
    _script("exit_pupil_figure.py")
    return ROOT / "docs" / "exit-pupil-error.png"


def microscope(docs: Path, work: Path) -> Path:
    _script("microscope_figure.py")
    return ROOT / "docs" / "microscope-geometry.png"


PICTURES = {"depth": depth_sample, "refocus": refocus_sample, "viewer": viewer, "exit-pupil": exit_pupil,
            "microscope": microscope}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=sorted(PICTURES), help="make only these pictures")
    parser.add_argument("--docs", default=str(ROOT / "docs"),
                        help="where the sample's pictures go (default docs/; the figures always go to docs/)")
    args = parser.parse_args()
    docs = Path(args.docs)
    docs.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="lfproc-docs-") as tmp:
        for name in args.only or PICTURES:
            path = PICTURES[name](docs, Path(tmp))
            if path is not None:
                print(f"{name}: {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
