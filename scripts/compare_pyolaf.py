"""lfproc's wave-optics forward model against pyolaf's, the same optics through both (issue 39, check 1).

    python scripts/compare_pyolaf.py --pyolaf-python /work/pyolaf-venv/bin/python [--json OUT.json]

The optics are the real sea-urchin rig of ../shared/real/lfm-seaurchin/metadata.txt (20x/0.5 water,
125 µm lenslets at f_s 2433 µm, 482 nm), resampled to 15 samples per lens, super-resolution 5, 11 planes
from −100 to 100 µm (the issue's settings), on 31 × 31 lenses. pyolaf 0.2.1 runs in its own venv
(scripts/pyolaf_reference.py); its lenslet focal length is given as n·f_s (its lenslet phase uses k = 2πn/λ).

Compared, per plane:

* the voxels' light-field PSFs (pyolaf's forward patterns H before its clamping, all 9 classes it computes)
  with lfproc's at pyolaf's sampling (the field at one point per pixel, ``oversample=1``) and at lfproc's
  own (the intensity integrated over each pixel, 3 × 3 sub-samples);
* forward projections through both programs' operators (pyolaf's clamped at 0.5 % of each pattern's
  peak, as it deconvolves): of one voxel (an off-centre class) and of a random volume in that plane.

Each as the normalised cross-correlation (NCC) and the relative L2 difference ‖a − b‖/‖b‖ (b pyolaf's, both
scaled to unit sum). Prints a Markdown table; ``--json`` writes the numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import lfproc  # noqa: E402
from lfproc.io import napari_camera  # noqa: E402
from lfproc.wave import Projector, build_operators  # noqa: E402

METADATA = os.path.join(ROOT, "..", "shared", "real", "lfm-seaurchin", "metadata.txt")
HELPER = os.path.join(ROOT, "scripts", "pyolaf_reference.py")


def urchin_camera(m_hat: int = 15) -> lfproc.Camera:
    camera, _ = napari_camera(METADATA)
    return dataclasses.replace(camera, micro_image_px=m_hat)


def optics_json(camera, z_um, superres: int, lenses: int) -> dict:
    w = camera.main_optics.wave_optics
    return {"M": w.objective_magnification, "NA": w.numerical_aperture, "n": w.immersion_index,
            "wavelength_um": w.wavelength_nm * 1e-3, "ftl_um": w.tube_lens_focal_length_mm * 1000.0,
            "pitch_um": camera.mla_pitch_mm * 1000.0, "fs_um": camera.mla_focal_length_mm * 1000.0,
            "spacing_px": camera.m_hat, "superres": superres, "depths_um": [float(z) for z in z_um],
            "image_px": [lenses * camera.m_hat, lenses * camera.m_hat]}


def pyolaf(python: str, mode: str, optics: dict, *files) -> dict:
    with tempfile.TemporaryDirectory() as folder:
        config, out = os.path.join(folder, "optics.json"), os.path.join(folder, "out.npz")
        with open(config, "w") as fh:
            json.dump(optics, fh)
        subprocess.run([python, HELPER, mode, config, *files, out], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        with np.load(out) as data:
            return {name: data[name] for name in data.files}


def closeness(a, b) -> tuple[float, float]:
    """(NCC, ‖a − b‖/‖b‖) of two arrays scaled to unit sum."""
    a = np.asarray(a, dtype=np.float64).ravel()
    b = np.asarray(b, dtype=np.float64).ravel()
    a, b = a / a.sum(), b / b.sum()
    ncc = float(np.corrcoef(a, b)[0, 1])
    return ncc, float(np.linalg.norm(a - b) / np.linalg.norm(b))


def pattern_image(kernel_views, views, m_hat: int, radius: int) -> np.ndarray:
    """An (m̂, m̂, K, K) pattern of the kept views as a rectified image (K·m̂)²."""
    k = 2 * radius + 1
    full = np.zeros((m_hat, m_hat, k, k))
    full[views[:, 0], views[:, 1]] = kernel_views
    return full.transpose(2, 0, 3, 1).reshape(k * m_hat, k * m_hat)


def compare_patterns(reference: dict, ops, superres: int) -> list:
    """Per plane, the worst (NCC, relative L2) over pyolaf's 9 classes (σ = −2…0 each way)."""
    half, m = int(reference["half"]), ops.m_hat
    step = m // superres
    r = ops.radius
    rows = []
    for c in range(len(ops.z_um)):
        worst = (1.0, 0.0)
        for i in range(3):
            for j in range(3):
                sy, sx = i, j                                       # class index; σ = index − 2
                mine = pattern_image(ops.kernels[c, sy * superres + sx], ops.views, m, r)
                theirs = reference[f"raw_{i}_{j}_{c}"].astype(np.float64)
                size = theirs.shape[0]
                canvas = np.zeros((size + 2 * mine.shape[0],) * 2)
                off = mine.shape[0]
                y0 = off + half - r * m - (m - 1) // 2 - step * (sy - 2)
                x0 = off + half - r * m - (m - 1) // 2 - step * (sx - 2)
                canvas[y0:y0 + mine.shape[0], x0:x0 + mine.shape[1]] = mine
                ncc, rel = closeness(canvas[off:off + size, off:off + size], theirs)
                worst = (min(worst[0], ncc), max(worst[1], rel))
        rows.append(worst)
    return rows


#: the test reference: (depth, pyolaf's class (i, j): σ = (i − 2, j − 2)) and the half size kept (pixels)
TEST_CASES = ((-60.0, (0, 1)), (0.0, (2, 2)), (40.0, (1, 0)))
TEST_HALF = 60


def write_test_reference(python: str, camera, path: str) -> int:
    """Three of pyolaf's PSFs (before its clamping) cropped to ±60 px around the voxel, for tests/test_wave_model.py."""
    depths = [case[0] for case in TEST_CASES]
    reference = pyolaf(python, "patterns", optics_json(camera, depths, 5, 15))
    half = int(reference["half"])
    patterns, offsets = [], []
    for c, (_, (i, j)) in enumerate(TEST_CASES):
        pattern = reference[f"raw_{i}_{j}_{c}"][half - TEST_HALF:half + TEST_HALF + 1, half - TEST_HALF:half + TEST_HALF + 1]
        patterns.append(pattern.astype(np.float32))
        offsets.append(((i - 2) * 25.0, (j - 2) * 25.0))
    np.savez_compressed(path, z_um=np.array(depths), offset_um=np.array(offsets), patterns=np.array(patterns),
                        half=np.full(len(depths), TEST_HALF), source=np.array("pyolaf 0.2.1, scripts/compare_pyolaf.py"))
    return 0


def rectified(views_data, views, m_hat: int, lens_shape) -> np.ndarray:
    ny, nx = lens_shape
    full = np.zeros((m_hat, m_hat, ny, nx))
    full[views[:, 0], views[:, 1]] = views_data
    return full.transpose(2, 0, 3, 1).reshape(ny * m_hat, nx * m_hat)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pyolaf-python", required=True, help="the Python of a venv with pyolaf 0.2.1")
    parser.add_argument("--lenses", type=int, default=31, help="lenses per side of the projections (default 31)")
    parser.add_argument("--json", help="write the numbers here")
    parser.add_argument("--write-test-reference", metavar="NPZ",
                        help="only write tests/data/pyolaf_psf.npz: three of pyolaf's PSFs, cropped")
    args = parser.parse_args(argv)
    camera = urchin_camera()
    if args.write_test_reference:
        return write_test_reference(args.pyolaf_python, camera, args.write_test_reference)
    superres, z = 5, np.arange(-100.0, 100.1, 20.0)
    optics = optics_json(camera, z, superres, args.lenses)
    reference = pyolaf(args.pyolaf_python, "patterns", optics)
    own = {1: build_operators(camera, z, superres, oversample=1), None: build_operators(camera, z, superres)}
    pattern_rows = {q: compare_patterns(reference, ops, superres) for q, ops in own.items()}

    n, s = args.lenses, superres
    rng = np.random.default_rng(39)
    volumes = {}
    for c in range(len(z)):
        point = np.zeros((n * s, n * s, len(z)), dtype=np.float32)
        point[(n // 2) * s + 2, (n // 2) * s + 4, c] = 1.0                 # a voxel off its lens centre
        random = np.zeros_like(point)
        random[:, :, c] = rng.random((n * s, n * s))
        volumes[f"point_{c}"], volumes[f"random_{c}"] = point, random
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "volumes.npz")
        np.savez(path, **volumes)
        projected = pyolaf(args.pyolaf_python, "project", optics, path)
    # pyolaf's lens (0, 0) has its centre pixel and voxel here; lfproc's at ((m̂ − 1)/2, (S − 1)/2)
    pixel_shift = projected["lens_px"][0, 0].astype(int) - (camera.m_hat - 1) // 2
    voxel_shift = projected["lens_vox"][0, 0].astype(int) - (s - 1) // 2
    assert not pixel_shift.any() and (voxel_shift >= 0).all(), (pixel_shift, voxel_shift)
    results = {"planes_um": z.tolist(), "patterns": {}, "point": {}, "random": {},
               "pyolaf_voxel_offset": voxel_shift.tolist()}
    for q, ops in own.items():
        label = "oversample 1 (pyolaf's sampling)" if q == 1 else f"oversample {ops.oversample} (lfproc's)"
        projector = Projector(ops, (n, n))
        results["patterns"][label] = pattern_rows[q]
        for kind in ("point", "random"):
            rows = []
            for c in range(len(z)):
                volume = np.zeros_like(volumes[f"{kind}_{c}"])           # (Y, X, Z): pyolaf's layout, moved
                dy, dx = voxel_shift
                volume[:volume.shape[0] - dy, :volume.shape[1] - dx] = volumes[f"{kind}_{c}"][dy:, dx:]
                poly = volume.transpose(2, 0, 1).reshape(len(z), n, s, n, s).transpose(0, 2, 4, 1, 3)
                image = rectified(projector.forward(poly.reshape(-1, n, n)), ops.views, ops.m_hat, (n, n))
                rows.append(closeness(image, projected[f"{kind}_{c}"]))
            results[kind][label] = rows
    print("| z (µm) | " + " | ".join(f"PSF {k}" for k in results["patterns"]) + " | "
          + " | ".join(f"{kind} {k}" for kind in ("point", "random") for k in results[kind]) + " |")
    print("|" + " --- |" * (1 + 3 * len(own)))
    for c, depth in enumerate(z):
        cells = [f"{results['patterns'][k][c][0]:.4f} / {results['patterns'][k][c][1]:.3f}" for k in results["patterns"]]
        cells += [f"{results[kind][k][c][0]:.4f} / {results[kind][k][c][1]:.3f}" for kind in ("point", "random")
                  for k in results[kind]]
        print(f"| {depth:+.0f} | " + " | ".join(cells) + " |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
