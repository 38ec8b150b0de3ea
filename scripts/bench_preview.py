#!/usr/bin/env python
"""What ``--preview`` costs against the refocus it illustrates (issue 32), in CPU seconds.

A microscope z-stack (the 60x water camera, 15 × 15 views, 41 slices over ±20 µm) of a smooth textured
light field of N × N lenses: refocusing and writing the slices (what ``lfproc refocus`` does without
``--preview``) against writing their previews (tone map, Lanczos enlargement to ≥ 512 px, labels, PNG).
CPU time (``time.process_time``) rather than wall time, so that a shared machine's load weighs less;
each figure is the best of ``--repeat`` runs, after one warm-up run (numba compiled).

Usage: ``PYTHONPATH=. python scripts/bench_preview.py [--lenses 28 136] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def light_field(n: int):
    from scipy.ndimage import gaussian_filter

    from lfproc import Camera, LightField

    camera = Camera.from_toml(ROOT / "lfproc" / "samples" / "cameras" / "lfm-60x-water.toml")
    m = camera.m_hat
    base = gaussian_filter(np.random.default_rng(0).random((n + 8, n + 8)), 1.5)
    views = np.stack([np.stack([base[4 + (ky - m // 2) // 4: 4 + (ky - m // 2) // 4 + n, 4:4 + n]
                                for _ in range(m)]) for ky in range(m)])
    return LightField.from_views(views[..., None].astype(np.float32), camera)


def measure(n: int, repeat: int) -> tuple[float, float]:
    from lfproc import geometry
    from lfproc.outputs import write_slice_previews, write_slices
    from lfproc.refocusing import refocus

    lf = light_field(n)
    a = list(geometry.plan_z_range(lf.camera, -20, 20, 1.0))
    refocus(lf, a, interpolation="cubic-spline")           # warm-up: numba compiles
    best_refocus = best_preview = np.inf
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as out:
            t0 = time.process_time()
            stack = refocus(lf, a, interpolation="cubic-spline")
            write_slices(out, "x", "x", lf.camera, a, stack)
            t1 = time.process_time()
            write_slice_previews(out, "x", stack, lf.camera, a, "png", view_mask=lf.view_mask)
            t2 = time.process_time()
        best_refocus, best_preview = min(best_refocus, t1 - t0), min(best_preview, t2 - t1)
    return best_refocus, best_preview


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lenses", type=int, nargs="+", default=[28, 136])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print("| lenses | slices | refocus + write, CPU s | previews, CPU s | ratio |")
    print("| --- | --- | --- | --- | --- |")
    for n in args.lenses:
        work, preview = measure(n, args.repeat)
        print(f"| {n} x {n} | 41 | {work:.2f} | {preview:.2f} | {preview / work:.2f} |")


if __name__ == "__main__":
    main()
