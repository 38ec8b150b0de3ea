"""The bundled simulated Lytro sample: what its script makes, and a refocus that finds its two planes."""

from __future__ import annotations

import hashlib
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT, SAMPLES
from lfproc import geometry, refocus
from lfproc.cli.lytro_defaults import camera_for_captures
from lfproc.api import prepare_decoding

LYTRO = SAMPLES / "lytro"


def test_sample_is_small_and_what_the_script_makes(tmp_path):
    files = sorted(p for p in LYTRO.rglob("*") if p.is_file())
    assert sum(p.stat().st_size for p in files) < 1_000_000
    assert sum(p.stat().st_size for p in SAMPLES.rglob("*") if p.is_file()) < 5_000_000
    before = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in files}
    proc = subprocess.run([sys.executable, str(ROOT / "scripts" / "make_lytro_sample.py")], capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr
    assert {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in files} == before


def test_sample_refocuses_on_each_plane(capsys):
    capture = str(LYTRO / "IMG_0001.lfr")
    camera = camera_for_captures(None, [capture])
    setup = prepare_decoding(camera, white_dir=str(LYTRO / "caldata"), captures=[capture], cache=True)
    assert "caldata/MOD_0000.RAW" in setup.white_note             # the matching zoom, not MOD_0001 (the commands print it)
    lf = setup.decode(capture)
    # the script put the planes where slices a = 1.25 (left half) and a = 0.25 (behind) focus: 9280.2 and
    # 45780.1 mm with its f_U 77.59 mm; the metadata's 77.5937 mm moves them by well under 1 %
    assert geometry.slice_distance_mm(camera, 1.25) == pytest.approx(9280.2, rel=0.01)
    assert geometry.slice_distance_mm(camera, 0.25) == pytest.approx(45780.1, rel=0.01)

    def sharpness(a, columns):
        image = refocus(lf, a).mean(axis=-1)
        return np.abs(np.diff(image[:, columns], axis=1)).mean()

    width = lf.views.shape[3]
    left, right = slice(2, width // 2 - 3), slice(width // 2 + 3, width - 2)
    assert sharpness(1.25, left) > 1.5 * sharpness(0.25, left)
    assert sharpness(0.25, right) > 1.5 * sharpness(1.25, right)
