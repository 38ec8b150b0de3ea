"""lfproc's wave-optics deconvolution against pyolaf's on the real sea urchin: time, memory, the volumes compared.

    python scripts/bench_deconvolution.py --pyolaf-python /work/pyolaf-venv/bin/python [--threads 1] \
        [--keep DIR [--reuse-pyolaf]] [--markdown docs/benchmarks-deconvolution.md] [--json docs/benchmarks-deconvolution.json]

The capture: ../shared/real/lfm-seaurchin (light_field.tif, radiometry_frame.tif as the white, dark_frame.tif,
the camera from napari-LF's metadata.txt), resampled to 15 samples per lens (the issue's settings: super-
resolution 5, 11 planes from −100 to 100 µm in steps of 20 µm, 8 Richardson–Lucy iterations, the
anti-aliasing filter on). Each run is its own process, measured by itself (CPU time user + system, peak
resident memory, wall time):

1. ``lfproc deconvolve`` end to end (decoding, the operators with an empty cache, 8 iterations, the files);
   then again with the operators in the cache (a rig's second capture);
2. lfproc's steps timed one by one (operators, projection set-up, each iteration), with the background at 0;
   then twice more for the comparison: at pyolaf's sampling (``oversample=1``), and "as pyolaf" — its sampling,
   its filter widths (oLaF's formula takes the depth in air, z·M², where the image lies z·M²/n behind the
   lenslets) and its update (its example divides by Hᵀ·H·1 and multiplies the ratio by H·1: Richardson–Lucy
   weighted by H·1);
3. pyolaf 0.2.1 (its own venv; scripts/pyolaf_reference.py) on the same measurement: lfproc's decoded light
   field as the rectified image at 15 pixels per lens (pyolaf's lenslet finder hangs on the full sea-urchin
   white, so lfproc's grid stands in for it), its operators, then Richardson–Lucy twice in the same process:
   as its example runs it ("example": its filter step ``abs(fftshift(ifft2(K·fft2(v))))`` moves the volume
   one voxel up and left at every iteration on odd-sized planes), and with that step centred ("centred":
   ``ifftshift`` in place of ``fftshift``, the one-voxel fix; nothing else changes).

The volumes are compared plane by plane (NCC after each plane is normalised; pyolaf's voxel grid is offset by
one voxel from lfproc's, which the comparison undoes), away from a border of 8 lenses, against each of
pyolaf's two loops. pyolaf takes about an hour on 2 loaded cores: ``--keep DIR --reuse-pyolaf`` keeps its
results in DIR and reuses them (``DIR/pyolaf_example.npz``, ``DIR/pyolaf_centred.npz``; a first-round
``DIR/pyolaf.npz`` counts as the example loop), running pyolaf only for a loop whose result is missing. ``--threads``
sets OPENBLAS_NUM_THREADS, OMP_NUM_THREADS and NUMBA_NUM_THREADS of every run (on a loaded machine, 1 keeps
the CPU times honest: BLAS threads that wait for a busy core spin). Writes the Markdown page and the JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
REAL = os.path.join(ROOT, "..", "shared", "real", "lfm-seaurchin")
HELPER = os.path.join(ROOT, "scripts", "pyolaf_reference.py")
Z_UM = [float(v) for v in range(-100, 101, 20)]
SUPERRES, ITERATIONS, M_HAT, BORDER_LENSES = 5, 8, 15, 8


def _usage() -> dict:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return {"cpu_s": r.ru_utime + r.ru_stime, "peak_rss_mb": r.ru_maxrss / 1024.0}


def camera_file(folder: str) -> str:
    """The sea urchin's camera from napari-LF's metadata, resampled to 15 samples per lens."""
    import dataclasses

    from lfproc.io import napari_camera

    camera, _ = napari_camera(os.path.join(REAL, "metadata.txt"))
    path = os.path.join(folder, "seaurchin.toml")
    with open(path, "w") as fh:
        fh.write(dataclasses.replace(camera, micro_image_px=M_HAT).to_toml())
    return path


def child_command(folder: str, cache: str) -> dict:
    """``lfproc deconvolve`` end to end, in this process."""
    from lfproc.cli import main

    os.environ["LFPROC_CACHE_DIR"] = cache
    start = time.perf_counter()
    status = main(["deconvolve", os.path.join(REAL, "light_field.tif"), "--camera", camera_file(folder), "--white",
                   os.path.join(REAL, "radiometry_frame.tif"), "--dark", os.path.join(REAL, "dark_frame.tif"),
                   "--white-is-white", "--z-range", "-100:100:20", "--superres", str(SUPERRES), "--iterations",
                   str(ITERATIONS), "-o", os.path.join(folder, "out")])
    return {"status": status, "wall_s": time.perf_counter() - start, **_usage()}


def olaf_widths(ops) -> np.ndarray:
    """oLaF's anti-aliasing widths (lfproc.wave.filter_widths with the depth in air: Δ = z·M²)."""
    import dataclasses

    from lfproc import wave

    voxels = np.floor(wave.filter_widths(dataclasses.replace(ops, immersion_index=1.0))).astype(int)
    return voxels + 1 - voxels % 2                       # oLaF rounds W down to an odd whole number


def child_steps(folder: str, variant: str) -> dict:
    """lfproc's steps one by one (``variant``: "default", "1" for oversample 1, "pyolaf" for pyolaf's sampling,
    widths and weights); saves the volume and the measurement (rectified) for pyolaf."""
    import warnings

    import lfproc
    from lfproc import wave
    from lfproc.api._deconvolve import _measurement

    warnings.simplefilter("ignore")
    q = None if variant == "default" else 1
    marks = {}

    def mark(name):
        marks[name] = (time.perf_counter(), _usage()["cpu_s"])

    mark("start")
    lf = lfproc.read_light_field(os.path.join(REAL, "light_field.tif"), camera_file(folder),
                                 white=os.path.join(REAL, "radiometry_frame.tif"),
                                 dark=os.path.join(REAL, "dark_frame.tif"), white_is_white=True)
    mark("decoded")
    ops = wave.build_operators(lf.camera, Z_UM, SUPERRES, oversample=q, lenses=min(lf.lens_shape))
    mark("operators")
    views, weights, data, _ = _measurement(lf, ops, 0.0)
    projector = wave.Projector(ops, lf.lens_shape, views)
    mark("projector")
    iteration_marks = []
    if variant == "pyolaf":
        weights = weights * projector.forward(np.ones((projector.inputs,) + lf.lens_shape, np.float32))
    volume, misfits = wave.richardson_lucy(projector, data, weights, 0.0, ITERATIONS, superres=SUPERRES,
                                           widths=olaf_widths(ops) if variant == "pyolaf" else wave.filter_widths(ops),
                                           callback=lambda *_: iteration_marks.append(time.perf_counter()))
    mark("iterations")
    np.save(os.path.join(folder, f"lfproc_volume_{variant}.npy"), volume)
    ny, nx = lf.lens_shape
    full = np.zeros((M_HAT, M_HAT, ny, nx), np.float32)
    picked = ops.views[views]
    full[picked[:, 0], picked[:, 1]] = data
    np.save(os.path.join(folder, "measurement.npy"), full.transpose(2, 0, 3, 1).reshape(ny * M_HAT, nx * M_HAT))

    def span(a, b):
        return {"wall_s": marks[b][0] - marks[a][0], "cpu_s": marks[b][1] - marks[a][1]}

    steps = np.diff([marks["projector"][0]] + iteration_marks).tolist()
    return {"decode": span("start", "decoded"), "operators": span("decoded", "operators"),
            "projector": span("operators", "projector"), "iterations": span("projector", "iterations"),
            "iteration_wall_s": steps, "misfits": misfits, "tile": projector.tile, "matrix_mb": projector.nbytes / 1e6,
            "kernels_mb": ops.kernels.nbytes / 1e6, "views": int(views.sum()), "oversample": ops.oversample,
            **_usage()}


def run_child(args: list, env: dict) -> dict:
    out = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", *args], env=env, check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def pyolaf_results(python: str, folder: str, env: dict, reuse: bool, loops=("example", "centred")) -> dict:
    """pyolaf's result per loop of ``loops`` ("example", "centred"): those kept in ``folder`` when ``reuse``, the
    others run (both loops in one process when both are missing: they share its operators)."""
    found = {}
    if reuse:
        for loop, names in (("example", ("pyolaf_example.npz", "pyolaf.npz")), ("centred", ("pyolaf_centred.npz",))):
            if loop not in loops:
                continue
            path = next((os.path.join(folder, n) for n in names if os.path.exists(os.path.join(folder, n))), None)
            if path is not None:
                with np.load(path) as data:
                    found[loop] = {name: data[name] for name in data.files}
                found[loop]["reused"] = True
    missing = [loop for loop in loops if loop not in found]
    if missing:
        found.update(run_pyolaf(python, folder, env, missing))
    return found


def run_pyolaf(python: str, folder: str, env: dict, loops: list) -> dict:
    from lfproc.io import napari_camera

    camera, _ = napari_camera(os.path.join(REAL, "metadata.txt"))
    w = camera.main_optics.wave_optics
    optics = {"M": w.objective_magnification, "NA": w.numerical_aperture, "n": w.immersion_index,
              "wavelength_um": w.wavelength_nm * 1e-3, "ftl_um": w.tube_lens_focal_length_mm * 1000.0,
              "pitch_um": camera.mla_pitch_mm * 1000.0, "fs_um": camera.mla_focal_length_mm * 1000.0,
              "spacing_px": M_HAT, "superres": SUPERRES, "depths_um": Z_UM, "iterations": ITERATIONS, "filter": True,
              "loops": list(loops)}
    config = os.path.join(folder, "pyolaf.json")
    with open(config, "w") as fh:
        json.dump(optics, fh)
    subprocess.run([python, HELPER, "deconvolve", config, os.path.join(folder, "measurement.npy"), folder], env=env,
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    results = {}
    for loop in loops:
        with np.load(os.path.join(folder, f"pyolaf_{loop}.npz")) as data:
            results[loop] = {name: data[name] for name in data.files}
    return results


def pyolaf_filter_shift(python: str, env: dict) -> dict:
    """How far one filter step of each loop moves a voxel (pyolaf's identity kernel on an odd plane): (y, x)."""
    with tempfile.TemporaryDirectory() as folder:
        config, out = os.path.join(folder, "none.json"), os.path.join(folder, "shift.npz")
        with open(config, "w") as fh:
            fh.write("{}")
        subprocess.run([python, HELPER, "filter-shift", config, out], env=env, check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        with np.load(out) as data:
            return {loop: [int(v) for v in data[f"shift_{loop}"]] for loop in ("example", "centred")}


def compare_volumes(mine: np.ndarray, theirs: np.ndarray, voxel_offset, shift=(0, 0)) -> list:
    """NCC per plane of two volumes (mine (Z, Y, X); pyolaf's (Y, X, Z), its voxel v at mine's v − offset, and
    moved by ``shift`` voxels), each plane standardised, away from the border."""
    dy, dx = (int(v) for v in voxel_offset)
    theirs = np.roll(np.moveaxis(theirs, 2, 0)[:, dy:, dx:], shift, axis=(1, 2))
    z, y, x = mine.shape
    h, w = min(y, theirs.shape[1]), min(x, theirs.shape[2])
    b = BORDER_LENSES * SUPERRES
    out = []
    for i in range(z):
        a, c = mine[i, b:h - b, b:w - b].astype(np.float64), theirs[i, b:h - b, b:w - b].astype(np.float64)
        a, c = (a - a.mean()) / (a.std() or 1.0), (c - c.mean()) / (c.std() or 1.0)
        out.append(float((a * c).mean()))
    return out


def figure(volume_path: str, png: str, planes=(0, 3, 5, 7, 10)) -> None:
    """Five planes of the command's volume and its maximum projection, side by side (each scaled to its
    99.8th percentile), half size: docs/deconvolution-seaurchin.png."""
    import tifffile
    from PIL import Image

    volume = tifffile.imread(volume_path)
    tiles = [volume[i] for i in planes] + [volume.max(axis=0)]
    row = np.concatenate([np.clip(t / max(np.percentile(t, 99.8), 1e-12), 0, 1) for t in tiles], axis=1)
    image = Image.fromarray((row * 255).astype(np.uint8))
    image.resize((row.shape[1] // 2, row.shape[0] // 2), Image.LANCZOS).save(png, optimize=True)


def markdown(results: dict) -> str:
    lf, po = results["lfproc_steps"], results.get("pyolaf")
    cold, warm = results["command_cold"], results["command_warm"]
    lines = ["# Benchmark: 3-D deconvolution of a light-field microscope capture, lfproc and pyolaf",
             "",
             "Generated by `python scripts/bench_deconvolution.py " + results["arguments"] + "` on "
             f"{results['date']} ({results['machine']}; load average {results['load_before']} before, "
             f"{results['load_after']} after; threads per run: {results['threads']}). The real sea urchin "
             "of ../shared/real/lfm-seaurchin (2048 × 2048, 8-bit), resampled to 15 samples per lens (117 × 117 "
             "lenses), super-resolution 5, 11 planes from −100 to 100 µm, 8 Richardson–Lucy iterations with the "
             "anti-aliasing filter: the settings of issue 39. CPU seconds are user + system of the run's own "
             "process; the machine was shared, so wall times are longer than the CPU's.", "",
             "| run | CPU s | wall s | peak memory MB |", "| --- | --- | --- | --- |",
             f"| `lfproc deconvolve`, end to end, operators not cached | {cold['cpu_s']:.1f} | {cold['wall_s']:.1f} | "
             f"{cold['peak_rss_mb']:.0f} |",
             f"| `lfproc deconvolve`, end to end, operators from the cache | {warm['cpu_s']:.1f} | {warm['wall_s']:.1f} | "
             f"{warm['peak_rss_mb']:.0f} |"]
    if po is not None:
        lines.append(f"| pyolaf 0.2.1, operators + 8 iterations (its process) | {float(po['cpu_s']):.1f} | "
                     f"{float(po['wall_s']):.1f} | {float(po['peak_rss_mb']):.0f} |")
    lines += ["", "Step by step (lfproc's steps in one process; pyolaf's from its own timers):", "",
              "| step | lfproc CPU s | lfproc wall s | pyolaf wall s |", "| --- | --- | --- | --- |",
              f"| decoding (lfproc; pyolaf is given the decoded, rectified light field) | {lf['decode']['cpu_s']:.1f} | "
              f"{lf['decode']['wall_s']:.1f} | — |",
              f"| operators (PSFs; pyolaf: geometry, PSFs, forward and backward patterns, H·1, Hᵀ·H·1) | "
              f"{lf['operators']['cpu_s'] + lf['projector']['cpu_s']:.1f} | "
              f"{lf['operators']['wall_s'] + lf['projector']['wall_s']:.1f} | "
              + (f"{float(po['operators_s']):.1f} |" if po is not None else "— |"),
              f"| one iteration (median) | {lf['iterations']['cpu_s'] / ITERATIONS:.2f} | "
              f"{float(np.median(lf['iteration_wall_s'])):.2f} | "
              + (f"{float(np.median(po['iteration_s'])):.1f} |" if po is not None else "— |"),
              f"| operators + 8 iterations | {lf['operators']['cpu_s'] + lf['projector']['cpu_s'] + lf['iterations']['cpu_s']:.1f} | "
              f"{lf['operators']['wall_s'] + lf['projector']['wall_s'] + lf['iterations']['wall_s']:.1f} | "
              + (f"{float(po['operators_s']) + float(np.sum(po['iteration_s'])):.1f} |" if po is not None else "— |")]
    if po is not None:
        ratio = results["ratio_cpu"]
        lines += ["", f"**lfproc's operators + 8 iterations took {ratio:.1f} × less CPU time than pyolaf's** "
                      f"({results['lfproc_cpu_s']:.1f} s against {results['pyolaf_cpu_s']:.1f} s, both measured in "
                      "their own process), with a peak memory of "
                      f"{cold['peak_rss_mb']:.0f} MB for the whole lfproc command against pyolaf's "
                      f"{float(po['peak_rss_mb']):.0f} MB."]
    lines += ["", f"lfproc's projections: tiles of {lf['tile']} × {lf['tile']} lenses, {lf['views']} views inside the "
                  f"NA, matrices {lf['matrix_mb']:.0f} MB, kernels {lf['kernels_mb']:.0f} MB, field sampled "
                  f"{lf['oversample']} × {lf['oversample']} per pixel. Misfit after each iteration: "
                  + ", ".join(f"{v:.3f}" for v in lf["misfits"]) + "."]
    if results.get("pyolaf_reused"):
        lines += ["", f"(pyolaf's {' and '.join(results['pyolaf_reused'])} loop(s) reused from an earlier run of this "
                      "script with the same settings: `--keep DIR --reuse-pyolaf`.)"]
    if "ncc" in results:
        step = results["pyolaf_filter_step_moves"]
        lines += ["", "The volumes, plane by plane (NCC after each plane is standardised, 8 lenses from the border "
                      "left out; both with the background at 0 and the filter on), against pyolaf's two loops. "
                      "\"example\": Richardson–Lucy as pyolaf's example runs it; its filter step "
                      "`abs(fftshift(ifft2(K·fft2(v))))` moves a voxel by "
                      f"{step['example']} (y, x) at every iteration on its odd-sized planes (measured with its own "
                      "`lanczosfft` and a single voxel), and the volume drifts. \"centred\": the same loop with "
                      f"`ifftshift` in that step (the one-voxel fix; a voxel moves by {step['centred']}), nothing "
                      "else changed. The acceptance of issue 39 is NCC ≥ 0.9 at matched planes."
                  + ("" if any(label.endswith("centred") for label in results["ncc"]) else
                     " (This run compared with the example's loop only: `--pyolaf-loops example`.)"), "",
                  "| z (µm) | " + " | ".join(f"{z:+.0f}" for z in Z_UM) + " |",
                  "| --- |" + " --- |" * len(Z_UM)]
        for label, values in results["ncc"].items():
            lines.append(f"| {label} | " + " | ".join(f"{v:.3f}" for v in values) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pyolaf-python", help="the Python of a venv with pyolaf 0.2.1 (without: lfproc only)")
    parser.add_argument("--threads", type=int, help="BLAS/OpenMP/numba threads of every run")
    parser.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks-deconvolution.md"))
    parser.add_argument("--json", default=os.path.join(ROOT, "docs", "benchmarks-deconvolution.json"))
    parser.add_argument("--keep", metavar="DIR", help="keep the volumes and pyolaf's results here (default: a "
                                                  "temporary folder)")
    parser.add_argument("--reuse-pyolaf", action="store_true",
                        help="with --keep DIR: reuse pyolaf's results kept there (pyolaf_example.npz, "
                             "pyolaf_centred.npz; a first-round pyolaf.npz counts as the example loop) and run pyolaf "
                             "only for a loop whose result is missing (pyolaf takes about an hour)")
    parser.add_argument("--pyolaf-loops", default="example,centred", choices=("example,centred", "example"),
                        help="pyolaf's loops to compare with (default both; the example's is needed for the timings)")
    parser.add_argument("--figure", default=os.path.join(ROOT, "docs", "deconvolution-seaurchin.png"),
                        help="the figure of the command's volume (default docs/deconvolution-seaurchin.png)")
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        kind, *rest = args.child
        result = child_command(*rest) if kind == "command" else child_steps(*rest)
        print(json.dumps(result))
        return 0
    env = dict(os.environ)
    if args.threads:
        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "MKL_NUM_THREADS"):
            env[name] = str(args.threads)
    shown = " ".join(a for a in (f"--threads {args.threads}" if args.threads else "",
                                 "--pyolaf-python PYTHON" if args.pyolaf_python else "",
                                 "--keep DIR" if args.keep else "", "--reuse-pyolaf" if args.reuse_pyolaf else "",
                                 f"--pyolaf-loops {args.pyolaf_loops}" if args.pyolaf_loops != "example,centred"
                                 else "") if a)
    results = {"date": time.strftime("%Y-%m-%d"), "machine": f"{platform.machine()}, {os.cpu_count()} CPUs",
               "load_before": round(os.getloadavg()[0], 1), "threads": args.threads or "default", "arguments": shown}
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.keep or scratch
        os.makedirs(folder, exist_ok=True)
        cache = os.path.join(scratch, "cache")
        results["command_cold"] = run_child(["command", folder, cache], env)
        results["command_warm"] = run_child(["command", folder, cache], env)
        figure(os.path.join(folder, "out", "light_field_volume.ome.tif"), args.figure)
        results["lfproc_steps_q1"] = run_child(["steps", folder, "1"], env)
        results["lfproc_steps_as_pyolaf"] = run_child(["steps", folder, "pyolaf"], env)
        results["lfproc_steps"] = run_child(["steps", folder, "default"], env)      # last: its measurement is pyolaf's
        lf = results["lfproc_steps"]
        results["lfproc_cpu_s"] = lf["operators"]["cpu_s"] + lf["projector"]["cpu_s"] + lf["iterations"]["cpu_s"]
        if args.pyolaf_python:
            loops = pyolaf_results(args.pyolaf_python, folder, env, args.reuse_pyolaf, args.pyolaf_loops.split(","))
            results["pyolaf_reused"] = [loop for loop, po in loops.items() if po.get("reused")]
            po = loops["example"]
            assert (po["lens_px"][0, 0] == (M_HAT - 1) // 2).all()   # pyolaf's lenses sit where lfproc's do
            offset = po["lens_vox"][0, 0] - (SUPERRES - 1) // 2
            labels = {"default": f"lfproc (its default: field {results['lfproc_steps']['oversample']}² per pixel)",
                      "1": "lfproc at pyolaf's sampling (1 per pixel)",
                      "pyolaf": "lfproc as pyolaf (its sampling, filter widths and update)"}
            volumes = {name: np.load(os.path.join(folder, f"lfproc_volume_{name}.npy")) for name in labels}
            results["ncc"] = {f"{label} vs pyolaf {loop}": compare_volumes(volumes[name], loops[loop]["volume"], offset)
                              for loop in loops for name, label in labels.items()}
            results["pyolaf_filter_step_moves"] = pyolaf_filter_shift(args.pyolaf_python, env)
            results["pyolaf"] = {key: (value.tolist() if isinstance(value, np.ndarray) and key != "volume" else value)
                                 for key, value in po.items() if key not in ("volume", "lens_px", "lens_vox")}
            results["pyolaf_cpu_s"] = float(po["cpu_s"])            # its process from the geometry to the last iteration
            results["ratio_cpu"] = results["pyolaf_cpu_s"] / results["lfproc_cpu_s"]
    results["load_after"] = round(os.getloadavg()[0], 1)
    page = markdown(results)
    with open(args.markdown, "w") as fh:
        fh.write(page)
    with open(args.json, "w") as fh:
        json.dump(results, fh, indent=1, default=float)
    print(page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
