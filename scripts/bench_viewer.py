#!/usr/bin/env python
"""Benchmark of ``lfproc viewer``'s page build on a Lytro-Illum-sized light field → docs/benchmarks-viewer.md.

Light field: 15 × 15 views of 434 × 625 × 3 float32 (0.73 GB): two textured planes (left half at
a = 1.0, right half at a = 0.25) on an Illum-like camera (14 µm… see ``illum_like_camera``), views
built by shifting the texture per view exactly as refocusing undoes it. Measured, each in a fresh
child process so that its peak memory (``ru_maxrss``) is the whole run's:

* ``build_page`` (what ``lfproc viewer`` does after decoding: depth-from-focus sweep, slice plan,
  refocused stack, 8-bit images of every slice and view inside the aperture, depth map, page);
  target ≤ 15 s on 2 cores;
* two floors, in the same child: one read of the light field (``views.sum(axis=(0, 1))``), and
  writing the page's images again from ready 8-bit pixels (encoding and disk, no computing);
* a straightforward implementation of the same page: every sweep slice refocused by its own call in
  full colour, each image sRGB-encoded in float64 (``lfproc.io.srgb_encode``) and saved as PNG one
  after the other.

Usage: ``python scripts/bench_viewer.py [--repeats N]``; about a minute. The machine may be shared:
rerun when numbers look noisy (the table gives the median and the minimum).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from lfproc.camera import MainLens

ROOT = Path(__file__).resolve().parent.parent
SHAPE = (15, 434, 625, 3)
TARGET_S = 15.0
PLANES_A = (1.0, 0.25)


def illum_like_camera():
    from lfproc import Camera

    # 1.4 µm pixels under 20 µm lenses (14.3 px, resampled to 15 × 15 views), f/2 micro lenses, a
    # 30 mm main lens at f/2 focused at about 3 m (b_U > f_U, so a_∞ = −0.5 < 0 as on an Illum)
    return Camera(0.0014, 0.02, 0.04, MainLens(30.0, 30.3, f_number=2.0), micro_image_px=15, name="illum-like")


def two_plane_lightfield():
    from lfproc import LightField

    m, ny, nx, ch = SHAPE
    c = (m - 1) // 2
    rng = np.random.default_rng(0)
    pad = 16
    texture = rng.random((ny + 2 * pad, nx + 2 * pad), dtype=np.float32)
    from scipy import ndimage

    texture = ndimage.gaussian_filter(texture, 1.2)
    texture = (texture - texture.min()) / np.ptp(texture)
    views = np.empty((m, m, ny, nx, ch), np.float32)
    tint = np.float32([1.0, 0.9, 0.8])
    half = nx // 2
    for ky in range(m):
        for kx in range(m):
            for (x0, x1), a in zip(((0, half), (half, nx)), PLANES_A):
                sy, sx = int(round(a * (ky - c))), int(round(a * (kx - c)))  # refocus at a undoes this shift
                patch = texture[pad + sy:pad + sy + ny, pad + x0 + sx:pad + x1 + sx]
                views[ky, kx, :, x0:x1] = patch[:, :, None] * tint
    return LightField.from_views(views, illum_like_camera())


def child(mode: str, outdir: str) -> dict:
    built = time.perf_counter()
    lf = two_plane_lightfield()
    start = time.perf_counter()
    floor_s = []
    for _ in range(3):
        t0 = time.perf_counter()
        lf.views.sum(axis=(0, 1))
        floor_s.append(time.perf_counter() - t0)
    result = {"floor_s": min(floor_s), "lf_build_s": start - built}
    t0 = time.perf_counter()
    if mode == "lfproc":
        from lfproc.viewer import build_page

        build_page(lf, outdir, source="synthetic", stem="illum")
    else:
        straightforward_page(lf, outdir)
    result["seconds"] = time.perf_counter() - t0
    result["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    result["files"] = sum(len(files) for _, _, files in os.walk(outdir))
    if mode == "lfproc":
        result["write_floor_s"] = write_floor(outdir)
    return result


def write_floor(outdir: str) -> float:
    """Seconds to write the page's images again from ready 8-bit pixels (Pillow, the page's own writer)."""
    from PIL import Image

    from lfproc.viewer._images import write_all

    paths = [os.path.join(folder, name) for folder, _, names in os.walk(outdir) for name in names
             if name.endswith((".png", ".jpg"))]
    pixels = {}
    for path in paths:
        with Image.open(path) as image:
            pixels[path] = np.asarray(image)
    t0 = time.perf_counter()
    write_all([(path, lambda p=path: pixels[p]) for path in paths])
    return time.perf_counter() - t0


def straightforward_page(lf, outdir: str) -> None:
    """The same images, the obvious way: one refocus call per sweep slice, float64 sRGB, PNG, one at a time."""
    from PIL import Image
    from scipy import ndimage

    from lfproc import geometry
    from lfproc.io import srgb_encode
    from lfproc.refocusing import refocus
    from lfproc.viewer._focus import sweep, sweep_range

    camera = lf.camera
    os.makedirs(os.path.join(outdir, "views"), exist_ok=True)
    scores = []
    for a in sweep(camera, *sweep_range(camera, lf.lens_shape)):
        grey = refocus(lf, float(a)).mean(axis=-1)
        gy, gx = np.gradient(grey)
        scores.append(ndimage.uniform_filter(gx ** 2 + gy ** 2, 9))
    best = np.argmax(np.stack(scores), axis=0)
    planned = geometry.plan_slices(camera, 300.0, 2000.0)
    top = float(np.percentile(lf.views, 99.5))
    for k, a in enumerate(planned):
        image = refocus(lf, float(a))
        Image.fromarray(np.round(srgb_encode(image / top) * 255).astype(np.uint8)).save(f"{outdir}/slice_{k}.png")
    keep = geometry.views_inside_aperture(camera)
    for ky, kx in np.argwhere(keep):
        pixels = np.round(srgb_encode(lf.views[ky, kx] / top) * 255).astype(np.uint8)
        Image.fromarray(pixels).save(f"{outdir}/views/{ky}_{kx}.png")
    Image.fromarray((best * 4).astype(np.uint8)).save(f"{outdir}/depth.png")


def run_child(mode: str) -> dict:
    with tempfile.TemporaryDirectory() as outdir:
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        proc = subprocess.run([sys.executable, __file__, "--child", mode, outdir], capture_output=True, text=True,
                              env=env, check=True)
        return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--child", nargs=2, metavar=("MODE", "OUTDIR"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(*args.child)))
        return
    sys.path.insert(0, str(ROOT / "scripts"))
    from benchlib import machine_info

    run_child("lfproc")  # warm-up: numba's on-disk cache, file system
    runs = [run_child("lfproc") for _ in range(args.repeats)]
    plain = run_child("straightforward")
    seconds = [r["seconds"] for r in runs]
    median, best = statistics.median(seconds), min(seconds)
    floor = min(r["floor_s"] for r in runs)
    write_floor = statistics.median(r["write_floor_s"] for r in runs)
    info = machine_info()
    verdict = "PASS" if median <= TARGET_S else "FAIL"
    lines = [
        "# Viewer benchmark",
        "",
        "`python scripts/bench_viewer.py` (this page is its output). A Lytro-Illum-sized light field, 15 × 15 "
        "views of 434 × 625 × 3 float32 (0.73 GB), two textured planes; `lfproc.viewer.build_page` is what "
        "`lfproc viewer` runs after decoding (add about 2 s for decoding a 41 Mpx capture with `--calib`, "
        "see [benchmarks.md](benchmarks.md)). Each run is a fresh process; peak memory is that process's "
        "maximum resident set, including the 0.73 GB light field itself.",
        "",
        "| case | time (median of %d) | minimum | × floor | peak memory | files |" % args.repeats,
        "| --- | --- | --- | --- | --- | --- |",
        f"| floor: one read of the light field (`views.sum(axis=(0, 1))`) | {floor:.3f} s | | 1 | | |",
        f"| floor: writing the page's images from ready 8-bit pixels | {write_floor:.2f} s | | "
        f"{write_floor / floor:.0f} | | {runs[0]['files'] - 2} |",
        f"| **lfproc viewer page** (target ≤ {TARGET_S:.0f} s: {verdict}) | {median:.2f} s | {best:.2f} s | "
        f"{median / floor:.0f} | {statistics.median(r['peak_rss_mb'] for r in runs):.0f} MB | {runs[0]['files']} |",
        f"| straightforward implementation (one call per slice, float64 sRGB, PNG, serial) | {plain['seconds']:.2f} s | "
        f"| {plain['seconds'] / floor:.0f} | {plain['peak_rss_mb']:.0f} MB | {plain['files']} |",
        "",
        f"lfproc is {plain['seconds'] / median:.1f} × faster than the straightforward implementation; "
        f"{write_floor / median:.0%} of its time is writing the images. The rest is the depth estimate (a sweep "
        f"of refocused slices, see docs/commands.md's viewer section), the refocused stack and the tone mapping.",
        "",
        f"Machine: {info['cpu_model']}, {info['cpus_usable']} usable cores, {info['memory_gb']:.0f} GB; "
        f"numba {info['numba']} ({info['numba_threads']} threads), numpy {info['numpy']}, Python {info['python']}; "
        f"load average at start {', '.join(f'{x:.1f}' for x in info['load_average_start'])}; {info['date']}.",
        "",
    ]
    out = ROOT / "docs" / "benchmarks-viewer.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
