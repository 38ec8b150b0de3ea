"""Whole commands on an Illum-sized capture: wall time, CPU time and peak memory of ``lfproc refocus``,
``views``, ``depth``, ``viewer`` and ``batch``, where the time goes inside them, and floors measured in the
same run.

    python scripts/bench_commands.py [--quick] [--out DIR] [--keep DIR] [--before CHECKOUT] [--markdown]
    python scripts/bench_commands.py --disk-only [--out DIR]
    python scripts/bench_commands.py --batch-only [--keep DIR] [--out DIR]
    python scripts/bench_commands.py --compare REV [--pairs N] [--keep DIR] [--out DIR]

The capture is a Lytro-Illum-like sensor (7728 × 5368 px, GRBG, 1.4 µm pixels under 20 µm hexagonal
lenses = 14.29 px, m̂ = 15 → a 15 × 15 × 434 × 625 × 3 light field) made here in a few seconds: a white
image of anti-aliased micro image disks on the exact lattice, and a capture that is that white image
times a smooth random texture, both 10-bit in 16-bit PNGs (kept in ``--keep DIR`` for the next run).

* **Commands**: each a fresh ``python -m lfproc`` process; wall time, CPU time (user + system, all
  threads) and peak memory (the maximum resident set size, ``getrusage(RUSAGE_CHILDREN)``: what a
  user's machine must hold). The decoder cache (``lfproc.decoder_cache``) lives in the work folder: the
  first ``refocus`` derives the decoder's state from the white image and stores it ("first run"), the
  later commands find it ("cache ready", the usual case after one command or ``lfproc calibrate``).
* **Phases**: one refocus done step by step in a fresh process, wall and CPU time per step.
* **Batch**: ``lfproc batch`` of N captures (links to the one capture) with one white image, with 1 and
  2 workers: seconds per capture and the speed-up.
* **Floors**, in the same run: Python starting and importing what the commands import; reading the
  capture PNG with OpenCV (``cv2.imread``, the PNG decoder alone); a fixed single-threaded numpy
  workload timed before and after (its wall/CPU ratio says how loaded the machine was: 1.0 is idle).
* **Disk** (full runs, ``--disk-only``): the views' 225 TIFFs against one ``tofile`` of the same bytes.
* ``--batch-only``: the batch runs again (with the load gauge around them), the other rows kept: for a
  quieter moment on a shared machine.
* ``--before CHECKOUT``: the same commands run on the code of another checkout (e.g. ``git worktree
  add /tmp/base COMMIT``), for the before/after table.
* ``--compare REV``: refocus and views of this tree against those of revision REV, N alternating pairs
  (default 4): the median ratio of the pairs (wall and CPU) and each side's peak memory
  (``scripts/bench_compare.py``); the other rows of the page are kept.

``--quick`` (about 2 minutes on 2 idle cores): refocus and views, the phases, a batch of 4 captures, no
disk, depth or viewer. Results go to ``DIR/benchmarks-commands.json`` and ``.md`` (``DIR`` is created; rows
of an earlier run that this run did not measure are kept); ``--markdown`` prints the tables to stdout.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from lfproc.camera import MainLens

ROOT = Path(__file__).resolve().parent.parent
SENSOR = (5368, 7728)
TARGETS = {"refocus_s": 5.0, "peak_gb": 1.5, "views_s": 5.0, "decode_s": 1.5, "batch_s_per_capture": 3.0,
           "batch_speedup": 1.7}


def illum_camera():
    from lfproc import Camera
    return Camera(0.0014, 0.02, 0.04, MainLens(50.0, 50.0, f_number=2.0), grid="hexagonal", cfa="GRBG", black_level=64.0, white_level=1023.0, micro_image_px=15, name="lytro-illum-like")


def lattice_distance(x, y, grid):
    """Distance of points to the nearest lens centre of a hexagonal ``grid`` (candidates around them)."""
    u, v = grid.axes
    dx, dy = x - grid.origin_xy_px[0], y - grid.origin_xy_px[1]
    row0 = np.floor((dx * v[0] + dy * v[1]) / grid.row_spacing_px)
    best = np.full(x.shape, np.inf)
    for step in (0.0, 1.0):
        row = row0 + step
        start = grid.lens_xy(row, np.zeros_like(row))
        col0 = np.floor(((x - start[..., 0]) * u[0] + (y - start[..., 1]) * u[1]) / grid.pitch_px)
        for cstep in (0.0, 1.0):
            centre = grid.lens_xy(row, col0 + cstep)
            best = np.minimum(best, np.hypot(x - centre[..., 0], y - centre[..., 1]))
    return best


def illum_frames(grid, black: float = 64.0) -> tuple[np.ndarray, np.ndarray]:
    """White image and capture (10-bit values in uint16) of the Illum-sized sensor: anti-aliased micro image
    disks on ``grid``'s exact lattice, the capture times a smooth random texture (also scripts/bench_decode.py)."""
    rng = np.random.default_rng(1)
    coarse = rng.random((SENSOR[0] // 64 + 2, SENSOR[1] // 64 + 2))
    white = np.empty(SENSOR, np.uint16)
    capture = np.empty(SENSOR, np.uint16)
    radius = 0.47 * grid.pitch_px
    for r0 in range(0, SENSOR[0], 512):
        rows = np.arange(r0, min(r0 + 512, SENSOR[0]), dtype=np.float64)
        y, x = np.meshgrid(rows, np.arange(SENSOR[1], dtype=np.float64), indexing="ij")
        lit = np.clip(radius - lattice_distance(x, y, grid) + 0.5, 0.0, 1.0)
        texture = 0.2 + 0.7 * coarse[(y / 64).astype(int), (x / 64).astype(int)]
        white[r0:r0 + len(rows)] = np.rint(black + 900 * lit)
        capture[r0:r0 + len(rows)] = np.rint(black + 900 * lit * texture)
    return white, capture


def illum_grid(camera):
    from lfproc import simulate
    return simulate.default_grid(camera, SENSOR, rotation_deg=-0.03, offset_px=(0.31, -0.17))


def make_capture(folder: Path) -> None:
    """White image, capture, camera and exact grid file of the Illum-like sensor (kept if already there); the
    grid file is laid out as ``lfproc calibrate`` writes it (one key per line), with the exact lattice."""
    from lfproc.gridfile import Calibration
    from lfproc.io import write_image

    names = ("white.png", "capture.png", "camera.toml", "grid.json")
    if all((folder / name).is_file() for name in names) and '"centers_xy_px": [[' in (folder / "grid.json").read_text():
        return
    camera = illum_camera()
    grid = illum_grid(camera)
    if not all((folder / name).is_file() for name in names[:2]):
        white, capture = illum_frames(grid)
        write_image(folder / "white.png", white)
        write_image(folder / "capture.png", capture)
    (folder / "camera.toml").write_text(camera.to_toml())
    exact = dataclasses.replace(grid, calibration=Calibration(white_image=str(folder / "white.png")))
    exact.save(folder / "grid.json")


# ----------------------------------------------------------------------------- measuring
def child_env(code: str | None, cache: Path, **extra) -> dict:
    """The environment of a measured process: whose code (PYTHONPATH, and the folder it runs in: see
    :func:`run_command`), which decoder cache."""
    env = dict(os.environ, LFPROC_CACHE_DIR=str(cache), PYTHONPATH=str(Path(code or ROOT).resolve()))
    env.pop("LFPROC_NO_CACHE", None)
    env.update(extra)
    return env


def run_command(argv: list[str], env: dict | None = None) -> dict:
    """Wall time, CPU time and peak RSS of one fresh process running ``argv`` (``python -m lfproc …`` if it
    starts with a command name).

    The process runs in the folder of the code it measures (``env``'s PYTHONPATH): ``python -m`` puts
    the working folder first on ``sys.path``, so run from another checkout it would import that
    checkout's lfproc, whatever PYTHONPATH says (how an earlier ``--before`` column measured the new
    code). Every path in ``argv`` is absolute."""
    cwd = (env or {}).get("PYTHONPATH", str(ROOT))
    if not argv[0].startswith("/"):
        argv = [sys.executable, "-m", "lfproc", *argv]
    code = ("import resource, subprocess, sys, time, json\n"
            "t = time.perf_counter()\n"
            "p = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
            "dt = time.perf_counter() - t\n"
            "r = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
            "print(json.dumps({'rc': p.returncode, 'seconds': dt, 'cpu_s': r.ru_utime + r.ru_stime,\n"
            "                  'peak_bytes': r.ru_maxrss * 1024, 'stderr': p.stderr[-800:], 'stdout': p.stdout[-4000:]}))\n")
    proc = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, check=True,
                          env=env, cwd=cwd)
    result = json.loads(proc.stdout)
    if result["rc"] != 0:
        raise SystemExit(f"{' '.join(argv[2:])} failed: {result['stderr']}")
    return result


def reference_load(seconds_of_work: int = 3) -> dict:
    """A fixed single-threaded numpy workload: wall/CPU says how loaded the machine is (1.0 = one idle core)."""
    rng = np.random.default_rng(0)
    data = rng.random(2_000_000)
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(12 * seconds_of_work):
        np.sort(data)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return {"wall_s": wall, "cpu_s": cpu, "load_factor": wall / cpu}


PHASES = r"""
import json, os, resource, sys, time
marks, t0, c0 = [], time.perf_counter(), time.process_time()
def mark(name):
    global t0, c0
    t, c = time.perf_counter(), time.process_time()
    marks.append({"phase": name, "wall_s": t - t0, "cpu_s": c - c0}); t0, c0 = t, c
folder, out = sys.argv[1], sys.argv[2]
import numpy, cv2, lfproc
from lfproc import Camera, LightField
from lfproc.io import read_capture
from lfproc import prepare_decoding
from lfproc.refocusing import refocus
from lfproc.outputs import write_slices
from lfproc.camera import MainLens
mark("imports (numpy, OpenCV, OpenImageIO, numba)")
camera = Camera.from_toml(os.path.join(folder, "camera.toml"))
setup = prepare_decoding(camera, grid=os.path.join(folder, "grid.json"), cache=True)
mark("camera, grid file, decoder (from the cache)")
capture = read_capture(os.path.join(folder, "capture.png"), camera)
mark("reading the capture PNG")
decoder = setup.decoder_for(capture.data.shape, capture.cfa)
views = decoder(capture.data, capture.cfa)
mark("decoding")
lf = LightField.from_views(views, camera, decoder.output_grid, decoder.views_delivered)
mark("building the LightField")
a = [-1.0, 0.0, 1.0, 2.0, 3.0]
stack = refocus(lf, a)
mark("refocusing 5 slices")
write_slices(out, "capture", "capture.png", camera, a, stack, "tiff")
mark("writing 5 slices + sidecars")
print(json.dumps({"phases": marks, "peak_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}))
"""


def phases(folder: Path, env: dict) -> dict:
    """Where the time of one refocus goes (cache ready): wall and CPU per step, in a fresh process."""
    out = folder / "phases"
    shutil.rmtree(out, ignore_errors=True)
    proc = subprocess.run([sys.executable, "-c", PHASES, str(folder), str(out)], capture_output=True, text=True,
                          env=env)
    if proc.returncode != 0:
        raise SystemExit(f"phase profile failed: {proc.stderr[-800:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def floors(folder: Path, env: dict) -> dict:
    """Python + imports in a fresh process; OpenCV's PNG decoder alone on the capture."""
    start = run_command([sys.executable, "-c", "import numpy, cv2, numba, OpenImageIO, lfproc.api"], env)
    png = run_command([sys.executable, "-c", f"import cv2; cv2.imread({str(folder / 'capture.png')!r}, "
                                             f"cv2.IMREAD_UNCHANGED)"], env)
    return {"imports_s": start["seconds"], "imports_cpu_s": start["cpu_s"], "png_read_s": png["seconds"],
            "png_read_cpu_s": png["cpu_s"]}


def command_cases(folder: Path, quick: bool) -> list[tuple[str, list[str], dict]]:
    """(label, argv, extra environment) of the measured commands, in the order run."""
    cap = [str(folder / "capture.png"), "--camera", str(folder / "camera.toml")]
    calib = [*cap, "--calib", str(folder / "grid.json")]
    cases = [("refocus --calib, 5 slices, first run (derives the decoder, caches it)",
              ["refocus", *calib, "--a", "-1:3", "-o", str(folder / "o-r0")], {}),
             ("refocus --calib, 5 slices (cache ready)", ["refocus", *calib, "--a", "-1:3", "-o", str(folder / "o-r1")],
              {}),
             ("views --calib, 225 TIFFs (cache ready)", ["views", *calib, "-o", str(folder / "o-v")], {})]
    if not quick:
        cases += [("refocus --white, 5 slices (calibrates; cache ready)",
                   ["refocus", *cap, "--white", str(folder / "white.png"), "--a", "-1:3", "-o", str(folder / "o-r2")],
                   {}),
                  ("refocus --calib, 5 slices, LFPROC_NO_CACHE=1 (derives every time)",
                   ["refocus", *calib, "--a", "-1:3", "-o", str(folder / "o-r3")], {"LFPROC_NO_CACHE": "1"}),
                  ("depth --calib (cache ready)", ["depth", *calib, "-o", str(folder / "o-d")], {}),
                  ("viewer --calib (cache ready)", ["viewer", *calib, "-o", str(folder / "o-w")], {})]
    return cases


def imported_lfproc(env: dict) -> str:
    """The folder of the lfproc a measured process imports (the checkout it is meant to measure)."""
    probe = run_command([sys.executable, "-c", "import lfproc, os; print(os.path.dirname(os.path.dirname("
                                               "os.path.abspath(lfproc.__file__))))"], env)
    return probe["stdout"].strip()


def describe_checkout(path: str) -> str:
    """``commit abc1234 (PATH)`` for a git checkout, else the path."""
    proc = subprocess.run(["git", "-C", path, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    return f"commit {proc.stdout.strip()} ({path})" if proc.returncode == 0 else path


def run_commands(folder: Path, code: str | None, quick: bool, tag: str) -> list[dict]:
    cache = folder / f"cache-{tag}"
    shutil.rmtree(cache, ignore_errors=True)
    env = child_env(code, cache)
    imported = imported_lfproc(env)
    if Path(imported).resolve() != Path(env["PYTHONPATH"]):
        raise SystemExit(f"[{tag}] the measured processes import lfproc from {imported}, not {env['PYTHONPATH']}")
    rows = []
    for label, argv, extra in command_cases(folder, quick):
        out = Path(argv[argv.index("-o") + 1])
        shutil.rmtree(out, ignore_errors=True)
        result = run_command(argv, child_env(code, cache, **extra))
        shutil.rmtree(out, ignore_errors=True)
        rows.append({"case": label, "seconds": result["seconds"], "cpu_s": result["cpu_s"],
                     "peak_gb": result["peak_bytes"] / 1e9})
        print(f"[{tag}] {label}: {result['seconds']:.1f} s (CPU {result['cpu_s']:.1f} s), "
              f"peak {result['peak_bytes'] / 1e9:.2f} GB", flush=True)
    return rows


#: the batch runs: (key, workers, extra environment); "one thread" keeps OpenCV and numba to one thread
BATCH_RUNS = (("workers_1", 1, {}), ("workers_1_one_thread", 1, {"NUMBA_NUM_THREADS": "1", "OPENCV_FOR_THREADS_NUM": "1"}),
              ("workers_2", 2, {}))


def batch(folder: Path, count: int, env: dict) -> dict:
    """``lfproc batch`` of ``count`` captures with one white image (cache ready): 1 worker (in the batch's own
    process, OpenCV's and numba's threads on every core), 1 worker with one thread, 2 worker processes."""
    inputs = folder / "batch-in"
    shutil.rmtree(inputs, ignore_errors=True)
    inputs.mkdir()
    for i in range(count):
        os.link(folder / "capture.png", inputs / f"c{i:02d}.png")
    result = {"captures": count}
    for key, workers, extra in BATCH_RUNS:
        out = folder / f"batch-out-{key}"
        shutil.rmtree(out, ignore_errors=True)
        run = run_command(["batch", *sorted(map(str, inputs.iterdir())), "--camera", str(folder / "camera.toml"),
                           "--calib", str(folder / "grid.json"), "--a", "-1:3", "--workers", str(workers), "-o",
                           str(out)], dict(env, **extra))
        shutil.rmtree(out, ignore_errors=True)
        result[key] = {"seconds": run["seconds"], "per_capture_s": run["seconds"] / count, "cpu_s": run["cpu_s"],
                       "peak_gb": run["peak_bytes"] / 1e9, "workers": workers, "one_thread": bool(extra)}
        print(f"batch of {count}, {key}: {run['seconds']:.1f} s, {run['seconds'] / count:.2f} s per capture, "
              f"CPU {run['cpu_s']:.1f} s", flush=True)
    shutil.rmtree(inputs, ignore_errors=True)
    result["speedup"] = result["workers_1"]["seconds"] / result["workers_2"]["seconds"]
    return result


def batch_lines(b: dict, cores: int | None) -> list[str]:
    """The batch table and what its numbers say about the 2-worker speed-up."""
    labels = {"workers_1": "1 (the batch's process, all threads)", "workers_1_one_thread": "1, one thread",
              "workers_2": "2 (processes, cores ÷ 2 threads each)"}
    lines = ["| workers | wall s | s per capture | CPU s | CPU s per capture | cores busy | peak GB (largest process) |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for key in ("workers_1", "workers_1_one_thread", "workers_2"):
        row = b.get(key)
        if row:
            lines.append(f"| {labels[key]} | {row['seconds']:.1f} | {row['per_capture_s']:.2f} | {row['cpu_s']:.1f} | "
                         f"{row['cpu_s'] / b['captures']:.2f} | {row['cpu_s'] / row['seconds']:.2f} | "
                         f"{row['peak_gb']:.2f} |")
    one, two = b["workers_1"], b["workers_2"]
    text = (f"2 workers: {b['speedup']:.2f}× one (target ≥ {TARGETS['batch_speedup']:g}×); target "
            f"≤ {TARGETS['batch_s_per_capture']:g} s per capture. *Cores busy* = CPU time ÷ wall time.")
    single = b.get("workers_1_one_thread")
    if single:
        text += (f" One worker gets {single['seconds'] / one['seconds']:.2f}× from its threads (OpenCV's remap and "
                 f"demosaicing, numba's refocusing): 2 workers run {single['seconds'] / two['seconds']:.2f}× one "
                 f"single-threaded worker, but against the threaded one a second process gains only the part of "
                 f"each capture that runs on one core.")
    growth = two["cpu_s"] / one["cpu_s"]
    text += (f" The 2 workers spent {growth:.2f}× the CPU time of one for the same captures " +
             ("(two processes share the memory bandwidth and caches; each starts, imports and reads the decoder "
              "cache once)" if growth > 1.02 else "(sharing the memory bandwidth cost them nothing measurable; "
                                                  "one worker's threads cost some CPU time of their own)"))
    if cores:
        text += (f", and kept {two['cpu_s'] / two['seconds']:.2f} of {cores} cores busy (anything below "
                 f"{min(cores, 2)} is time the workers waited: for the machine's other work, the disk, or the "
                 "batch's own process)")
    lines += ["", text + "."]
    return lines


def disk_floor_and_views(folder: Path, repeats: int = 3) -> dict:
    """Bytes per second of one big tofile vs all views through write_views (both synced), measured
    alternately ``repeats`` times (the page cache and the disk's write-back make single runs noisy);
    minima, every run kept in the results."""
    from lfproc.outputs import write_views

    camera = illum_camera()
    views = np.random.default_rng(2).random((15, 15, 434, 625, 3), dtype=np.float32)
    floors_s, times, written, paths = [], [], 0, []
    for r in range(repeats):
        os.sync()
        t = time.perf_counter()
        with open(folder / "floor.bin", "wb") as fh:
            views.tofile(fh)
        os.sync()
        floors_s.append(time.perf_counter() - t)
        (folder / "floor.bin").unlink()
        os.sync()
        t = time.perf_counter()
        paths = write_views(str(folder / f"views{r}"), "bench", "bench", camera, views, "tiff")
        os.sync()
        times.append(time.perf_counter() - t)
        written = sum(os.path.getsize(p) for p in paths)
        shutil.rmtree(folder / f"views{r}")
    floor_s, views_s = min(floors_s), min(times)     # the least disturbed runs (the disk warms up between runs)
    return {"bytes": int(views.nbytes), "files": len(paths), "tiff_bytes": written, "floor_s": floor_s,
            "views_s": views_s, "floor_mb_s": views.nbytes / floor_s / 1e6, "views_mb_s": written / views_s / 1e6,
            "ratio": (written / views_s) / (views.nbytes / floor_s), "repeats": repeats,
            "floor_runs_s": floors_s, "views_runs_s": times}


# ----------------------------------------------------------------------------- results
def merge_results(previous: dict | None, new: dict) -> dict:
    """The results to write: this run's sections, and those of ``previous`` (an earlier run's JSON, or None)
    that this run did not measure (a ``--disk-only`` or ``--quick`` run keeps the other rows)."""
    merged = dict(previous or {})
    merged.update({key: value for key, value in new.items() if value is not None})
    return merged


#: the profile in issue 24, before this work (same capture, 2 cores, one run each)
BEFORE_PROFILE = [
    ("`lfproc refocus CAP --camera C --calib GRID.json --a 0:2:0.5`", "10.7–11.6 s, 2.08 GB",
     "preparing the decoder from the white image 4.1 s (its inverse alone 3.6 s), decoding 2.8 s, reading "
     "capture and white PNG 1.8 s, building the LightField 0.8 s, refocus + writing ≈ 0.6 s"),
    ("the same with `--white` (calibrates too)", "10.3 s, 2.12 GB", ""),
    ("`lfproc views …` (225 TIFFs)", "8.3 s, 2.02 GB", ""),
]
#: the phases of PHASES that every decoding command shares (up to the LightField)
SHARED_PHASES = 5


def _row(label: str, now: dict, before: dict | None, target: str, shared_cpu: float | None) -> str:
    was = "—"
    if before:
        cpu_then = f", {before['cpu_s']:.1f} s CPU" if "cpu_s" in before else ""
        was = f"{before['seconds']:.1f} s{cpu_then}, {before['peak_gb']:.2f} GB"
    cpu = f"{now['cpu_s']:.1f}" if "cpu_s" in now else "—"
    where = ""
    if shared_cpu is not None and "cpu_s" in now and "first run" not in label and "NO_CACHE" not in label \
            and "--white" not in label:
        where = f"decode path {shared_cpu:.1f} s CPU + the command's own work {max(0.0, now['cpu_s'] - shared_cpu):.1f} s"
    return (f"| `lfproc {label}` | {was} | {now['seconds']:.1f} | {cpu} | {now['peak_gb']:.2f} | {where} | "
            f"{target} |")


def targets_table(r: dict) -> list[str]:
    """The issue's targets against this run: wall, CPU, and wall divided by the run's load factor."""
    load = r.get("load") or {}
    factor = min(load["before"]["load_factor"], load["after"]["load_factor"]) if load else 1.0
    rows = {row["case"]: row for row in r.get("commands") or []}
    phase = {p["phase"]: p for p in (r.get("phases") or {}).get("phases", [])}
    checks = []
    refocus = rows.get("refocus --calib, 5 slices (cache ready)")
    if refocus:
        checks.append(("`lfproc refocus`, saved calibration", f"≤ {TARGETS['refocus_s']:g} s",
                       refocus["seconds"], refocus.get("cpu_s"), TARGETS["refocus_s"]))
        checks.append(("… its peak memory", f"≤ {TARGETS['peak_gb']:g} GB", None, None, None,
                       refocus["peak_gb"] <= TARGETS["peak_gb"], f"{refocus['peak_gb']:.2f} GB"))
    views = rows.get("views --calib, 225 TIFFs (cache ready)")
    if views:
        checks.append(("`lfproc views`", f"≤ {TARGETS['views_s']:g} s", views["seconds"], views.get("cpu_s"),
                       TARGETS["views_s"]))
    if "decoding" in phase:
        checks.append(("decoding (a phase of refocus)", f"≤ {TARGETS['decode_s']:g} s", phase["decoding"]["wall_s"],
                       phase["decoding"]["cpu_s"], TARGETS["decode_s"]))
    if r.get("batch"):
        b = r["batch"]
        one = b["workers_1"]
        checks.append((f"batch of {b['captures']}, per capture (1 worker)", f"≤ {TARGETS['batch_s_per_capture']:g} s",
                       one["per_capture_s"], one["cpu_s"] / b["captures"], TARGETS["batch_s_per_capture"]))
        checks.append(("batch, 2 workers against 1", f"≥ {TARGETS['batch_speedup']:g}×", None, None, None,
                       b["speedup"] >= TARGETS["batch_speedup"], f"{b['speedup']:.2f}×"))
    lines = ["| target | goal | wall s | CPU s | wall ÷ load factor | met |", "| --- | --- | --- | --- | --- | --- |"]
    for check in checks:
        if check[2] is None:
            name, goal, _, _, _, ok, value = check
            lines.append(f"| {name} | {goal} | {value} | | | {'yes' if ok else 'no'} |")
            continue
        name, goal, wall, cpu, limit = check
        estimate = wall / factor
        verdict = "yes" if wall <= limit else ("by CPU time (the machine was loaded)" if cpu is not None and cpu <= limit
                                               else "no")
        lines.append(f"| {name} | {goal} | {wall:.2f} | {'—' if cpu is None else f'{cpu:.2f}'} | {estimate:.2f} | "
                     f"{verdict} |")
    return lines


def markdown(r: dict) -> str:
    """The benchmark page (docs/benchmarks-commands.md) from the results."""
    load = r.get("load") or {}
    lines = ["# Whole commands on an Illum-sized capture", "",
             f"Made by `python scripts/bench_commands.py{' --quick' if r.get('quick') else ''}` on {r.get('date')} "
             f"({r.get('machine')}). Sensor {SENSOR[1]} × {SENSOR[0]} px, hexagonal 14.29 px lenses, GRBG, "
             "m̂ = 15 → a 15 × 15 × 434 × 625 × 3 light field. Each command is a fresh process; peak = its "
             "maximum resident memory; CPU = user + system time of all its threads."]
    if load:
        lines += ["", f"Load: a fixed single-threaded numpy workload took {load['before']['load_factor']:.1f}× "
                      f"(before the commands) and {load['after']['load_factor']:.1f}× (after) its CPU time in wall "
                      "time (1.0 = an idle core): wall times below are inflated by about that much; CPU times "
                      "and memory are not."]
    if r.get("note"):
        lines += ["", r["note"]]
    if r.get("commands") and r.get("load"):
        lines += ["", "## Targets (issue 24)", "", *targets_table(r), "",
                  "*wall ÷ load factor* divides the wall time by the slowdown the load gauge measured in this run: "
                  "a rough estimate of the wall time on an idle machine. On a shared machine the CPU time (user + "
                  "system, all threads) is the steadier measure: a command that is mostly single-threaded, as these "
                  "are outside OpenCV's and numba's loops, takes about its CPU time on idle cores (less where those "
                  "loops run on both). *by CPU time*: the wall time missed the target on the loaded machine, the CPU "
                  "time meets it."]
    if r.get("commands"):
        before = {row["case"]: row for row in r.get("before_commands") or []}
        targets = {"refocus --calib, 5 slices (cache ready)": f"≤ {TARGETS['refocus_s']:g} s, "
                                                              f"≤ {TARGETS['peak_gb']:g} GB",
                   "views --calib, 225 TIFFs (cache ready)": f"≤ {TARGETS['views_s']:g} s"}
        phase_list = (r.get("phases") or {}).get("phases")
        shared = sum(p["cpu_s"] for p in phase_list[:SHARED_PHASES]) if phase_list else None
        lines += ["", "## Commands, before and after", "",
                  "| command | before (wall, CPU, peak) | wall s | CPU s | peak GB | where the CPU time goes | target |",
                  "| --- | --- | --- | --- | --- | --- | --- |"]
        for row in r["commands"]:
            lines.append(_row(row["case"], row, before.get(row["case"]), targets.get(row["case"], ""), shared))
        lines += ["", "*Decode path*: the CPU time of the first phases below (starting, imports, the decoder from the "
                      "cache, reading the capture, decoding, the LightField), which every decoding command shares; "
                      "the rest is the command's own work (refocusing, depth sweep, viewer images, writing)."]
        if r.get("before_code"):
            lines += ["", f"*Before*: the same commands on the code of {r['before_code']} (no decoder cache: every "
                          "command derives the decoder; it ignores `LFPROC_NO_CACHE`), in the same run."]
        lines += ["", "The profile of issue 24, before this work (one run each, a less loaded machine):", "",
                  "| command | then | where the time went |", "| --- | --- | --- |"]
        lines += [f"| {c} | {t} | {w} |" for c, t, w in BEFORE_PROFILE]
    if r.get("floors"):
        f = r["floors"]
        lines += ["", "Floors measured in the same run: Python starting and importing numpy, OpenCV, numba, "
                      f"OpenImageIO and lfproc.api {f['imports_s']:.2f} s (CPU {f['imports_cpu_s']:.2f} s); "
                      f"decoding the capture PNG with `cv2.imread` alone {f['png_read_cpu_s']:.2f} s CPU "
                      "(including that process's start)."]
    if r.get("phases"):
        p = r["phases"]
        lines += ["", "## Where the time of a refocus goes (cache ready)", "",
                  "One `lfproc refocus --calib` done step by step in a fresh process (scripts/bench_commands.py, "
                  "`PHASES`):", "", "| phase | wall s | CPU s |", "| --- | --- | --- |"]
        lines += [f"| {ph['phase']} | {ph['wall_s']:.2f} | {ph['cpu_s']:.2f} |" for ph in p["phases"]]
        total_w = sum(ph["wall_s"] for ph in p["phases"])
        total_c = sum(ph["cpu_s"] for ph in p["phases"])
        lines += [f"| total (peak {p['peak_bytes'] / 1e9:.2f} GB) | {total_w:.2f} | {total_c:.2f} |"]
        largest = sorted(p["phases"], key=lambda ph: -ph["cpu_s"])[:3]
        lines += ["", "The next bottlenecks, by CPU time: " + "; ".join(
            f"{ph['phase']} {ph['cpu_s']:.2f} s ({100 * ph['cpu_s'] / total_c:.0f} %)" for ph in largest) + "."]
    if r.get("batch"):
        b = r["batch"]
        lines += ["", f"## Batch: {b['captures']} captures, one white image (cache ready)", ""]
        if r.get("batch_load"):
            bl = r["batch_load"]
            lines += [f"Run again on its own (`--batch-only`): the load gauge read {bl['before']['load_factor']:.1f}× "
                      f"before and {bl['after']['load_factor']:.1f}× after these runs.", ""]
        lines += batch_lines(b, r.get("cores"))
    if r.get("disk"):
        d = r["disk"]
        lines += ["", "## Writing the views against the disk", "",
                  "225 float32 TIFFs, uncompressed, with sidecars, two files at a time, against the disk's "
                  "sequential write speed measured in the same run (the same number of bytes in one `tofile`, "
                  f"both synced; the fastest of {d['repeats']} alternating runs):", "",
                  "| what | MB | s | MB/s | share of the floor |", "| --- | --- | --- | --- | --- |",
                  f"| floor: one file, `numpy.tofile` + sync | {d['bytes'] / 1e6:.0f} | {d['floor_s']:.2f} | "
                  f"{d['floor_mb_s']:.0f} | 100 % |",
                  f"| `write_views`: {d['files']} TIFFs + sidecars + sync | {d['tiff_bytes'] / 1e6:.0f} | "
                  f"{d['views_s']:.2f} | {d['views_mb_s']:.0f} | {100 * d['ratio']:.0f} % (target ≥ 50 %) |", "",
                  "All runs, s (floor / views, in the order run): "
                  + ", ".join(f"{a:.2f} / {b:.2f}" for a, b in zip(d["floor_runs_s"], d["views_runs_s"]))
                  + ". The virtual disk here speeds up from run to run, so single runs mislead."]
    if r.get("compare"):
        from bench_compare import compare_lines

        lines += compare_lines(r["compare"])
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs"), help="folder of the results (created; default docs/)")
    parser.add_argument("--keep", help="work folder to keep, with the generated capture (default: a temporary one)")
    parser.add_argument("--quick", action="store_true", help="refocus, views, phases and a batch of 4 only")
    parser.add_argument("--before", metavar="CHECKOUT", help="also run the commands on this checkout's code")
    parser.add_argument("--batch", type=int, metavar="N", help="captures in the batch (default 20, --quick 4)")
    parser.add_argument("--disk-only", action="store_true", help="only the view-writing measurement")
    parser.add_argument("--batch-only", action="store_true", help="only the batch runs (and the load gauge)")
    parser.add_argument("--compare", metavar="REV", help="only the A/B of refocus and views against revision REV")
    parser.add_argument("--pairs", type=int, default=4, metavar="N", help="alternating pairs of --compare (default 4)")
    parser.add_argument("--note", default="", help="a paragraph for the page about this run (e.g. the machine's load)")
    parser.add_argument("--markdown", action="store_true", help="also print the tables (markdown) to stdout")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    folder = Path(args.keep or tempfile.mkdtemp(prefix="lfproc-bench-")).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    new = {"date": time.strftime("%Y-%m-%d"), "machine": f"{platform.machine()}, {os.cpu_count()} CPUs",
           "cores": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count(),
           "sensor": list(SENSOR), "note": args.note}
    try:
        if args.compare:
            from bench_compare import compare

            make_capture(folder)
            load_before = reference_load()
            result = compare(ROOT, folder, args.compare, args.pairs, run_command, child_env)
            result.update(date=new["date"], note=args.note, load={"before": load_before, "after": reference_load()})
            new["compare"] = {args.compare: result}
        elif args.batch_only:
            make_capture(folder)
            load_before = reference_load()
            new["batch"] = batch(folder, args.batch or 20, child_env(None, folder / "cache-now"))
            new["batch_load"] = {"before": load_before, "after": reference_load()}
        elif not args.disk_only:
            t = time.perf_counter()
            make_capture(folder)
            print(f"capture ready in {time.perf_counter() - t:.1f} s", flush=True)
            new["quick"] = args.quick
            load_before = reference_load()
            new["commands"] = run_commands(folder, None, args.quick, "now")
            if args.before:
                new["before_commands"] = run_commands(folder, args.before, args.quick, "before")
                new["before_code"] = describe_checkout(args.before)
            env = child_env(None, folder / "cache-now")
            new["phases"] = phases(folder, env)
            new["floors"] = floors(folder, env)
            new["batch"] = batch(folder, args.batch or (4 if args.quick else 20), env)
            new["load"] = {"before": load_before, "after": reference_load()}
        if args.disk_only or not (args.quick or args.batch_only or args.compare):
            new["disk"] = disk_floor_and_views(folder)
    finally:
        if not args.keep:
            shutil.rmtree(folder, ignore_errors=True)
    json_path = out / "benchmarks-commands.json"
    previous = json.loads(json_path.read_text()) if json_path.is_file() else None
    if previous and new.get("compare"):     # earlier comparisons against other revisions are kept
        new["compare"] = {**previous.get("compare", {}), **new["compare"]}
        new = {key: value for key, value in new.items() if key in ("compare",)}
    results = merge_results(previous, new)
    if "batch" in new and "batch_load" not in new:      # a full run's batch: no note of an earlier batch-only run
        results.pop("batch_load", None)
    json_path.write_text(json.dumps(results, indent=1) + "\n")
    page = markdown(results)
    (out / "benchmarks-commands.md").write_text(page)
    if args.markdown:
        print(page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
