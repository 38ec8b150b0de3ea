"""``lfproc batch``: refocus and extract views from many captures, locally or on a Dask cluster; resumable."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import os
import signal
import sys
import time

from ..errors import LfprocError
from .capture_loop import add_decode_options, add_output_folder_option, require_output_folder
from .common import add_aperture_option, add_slice_options, check_slice_options, describe_slices
from .deconvolve import add_deconvolution_options, deconvolution_settings
from .refocus import add_render_options, check_render_options
from .views import add_view_options, check_view_options
from .words import command_words


def register(sub) -> None:
    p = sub.add_parser("batch", help="process folders of captures in parallel (local or Dask), resumable",
                       description="Refocus, extract the views of and/or deconvolve many captures: inputs are files, "
                                   "folders or glob patterns. Outputs and sidecars are those of lfproc refocus, lfproc "
                                   "views and lfproc deconvolve, and every per-capture option of those commands means "
                                   "the same here (a time-lapse's deconvolution operators are built once, here, and "
                                   "shared by every worker). "
                                   "A manifest (OUTDIR/lfproc-manifest.json) records each capture; a rerun skips "
                                   "completed captures whose inputs and parameters are unchanged. A capture that "
                                   "fails is recorded with its error and the rest complete; the exit status is 2 "
                                   "if any failed, 130 if interrupted (rerun to resume).",
                       epilog=BATCH_GUIDE, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="capture files (or .lfp.npz light fields), folders or glob patterns")
    add_decode_options(p)
    add_output_folder_option(p)
    which = add_slice_options(p)
    which.add_argument("--refocus", dest="a", metavar="LIST", help=argparse.SUPPRESS)  # the old name of --a
    add_render_options(p)
    p.add_argument("--views", action="store_true", help="also write every viewpoint image (as lfproc views)")
    add_view_options(p)
    p.add_argument("--deconvolve", action="store_true",
                   help="also deconvolve each capture into a volume (as lfproc deconvolve; microscopes): --z-range "
                        "Z0:Z1:STEP gives its planes, and the options below shape it")
    add_deconvolution_options(p)
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: from the cores and the memory a capture needs; "
                        "1 = in this process, with multi-threaded refocusing)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on a dask.distributed cluster instead, e.g. tcp://host:8786 (shared file system)")
    add_aperture_option(p)
    p.set_defaults(func=run)


BATCH_GUIDE = """\
examples:
  lfproc batch shots/ --camera cam.toml --white white.png --a 0:3:0.5 -o out/        all cores of this machine
  lfproc batch 'shots/*/raw_*.dng' --camera cam.toml --calib grid.json --views -o out/
  lfproc batch shots/ ... --scheduler tcp://host:8786 -o /shared/out/                  a Dask cluster
  lfproc batch frames/ --camera lfm.toml --white white.tif --deconvolve --z-range -100:100:20 -o vols/
                                                  a time-lapse into volumes, the operators built once
inputs: files, folders (not recursive) and quoted glob patterns; .lfp.npz light fields need no camera,
  grid or white image; Lytro captures need no --camera and take --white-dir.
outputs: exactly those of lfproc refocus / views / deconvolve, per capture STEM_a+1.500.tif,
  STEM_view_KY_KX.tif, STEM_volume.ome.tif, each with its NAME.json sidecar;
  OUTDIR/lfproc-manifest.json records every capture.
resuming: a rerun skips captures whose outputs are complete and whose inputs and options are unchanged;
  it redoes the rest. Ctrl-C stops cleanly (exit 130); rerun the same command to finish.
exit status: 0 all done or skipped, 2 a capture failed or bad input (one line each), 130 interrupted.
(This text is the guide a wheel install carries; a source checkout has more in docs/batch.md.)"""


def _abs(path):
    return None if path is None else os.path.abspath(path)


def run(args) -> int:
    from .. import batch
    from ..camera import Camera
    from ..lightfield import LightField, is_lightfield_file
    from ..outputs import unique_stems
    from .lytro_defaults import camera_for_captures, white_image_for
    from .common import aperture_extent, slice_parameters

    check_render_options(args)
    check_slice_options(args)
    sources = _without_pictures(args.inputs, batch.expand_inputs(args.inputs))
    to_decode = [s for s in sources if not is_lightfield_file(s)]
    if to_decode and not (args.grid or args.white or args.white_dir):
        raise LfprocError("give --white WHITE (a white image), --white-dir DIR (a Lytro calibration folder) or "
                          "--calib GRID.json (from lfproc calibrate)")
    for path, flag in ((args.grid, "--calib"), (args.white, "--white"), (args.camera, "--camera"),
                       (args.dark, "--dark")):
        if path is not None and not os.path.isfile(path):
            raise LfprocError(f"{path}: {flag} file not found; check the path")
    if args.deconvolve and args.z_range_um is None:
        raise LfprocError("--deconvolve needs --z-range Z0:Z1:STEP (the volume's planes, micrometres from the native "
                          "object plane)")
    if args.deconvolve and args.aperture is not None:
        raise LfprocError("--aperture shapes refocused slices; with --deconvolve --z-range gives the volume's planes: "
                          "drop --aperture (refocus in another batch)")
    if args.a is None and args.depth_range_mm is None and args.distance_mm is None and args.z_range_um is None and not args.views:
        raise LfprocError("nothing to do: give --a LIST, --depth-range NEAR:FAR, --at MM, --z-range Z0:Z1 "
                          "and/or --views (or --deconvolve --z-range Z0:Z1:STEP)")
    if args.aperture is not None and args.a is None and args.depth_range_mm is None and args.distance_mm is None \
            and args.z_range_um is None:
        raise LfprocError("--aperture shapes the refocused slices: add --a, --depth-range, --at or --z-range")
    if (args.mosaic or args.gif or args.inside_aperture) and not args.views:
        raise LfprocError("--mosaic, --gif and --inside-aperture shape the views: add --views")
    if args.workers is not None and args.workers < 1:
        raise LfprocError(f"--workers must be >= 1, got {args.workers}")
    if args.workers is not None and args.scheduler:
        raise LfprocError("--workers sizes local processing; with --scheduler the cluster's workers run the "
                          "captures (start them with 'dask worker --nworkers N'): drop one of the two")
    if args.camera:
        camera = Camera.from_toml(args.camera)
        with open(args.camera, encoding="utf-8") as fh:
            camera_toml = fh.read()
    elif to_decode:   # Lytro captures carry their camera in their metadata; anything else needs --camera
        camera = camera_for_captures(None, to_decode)
        camera_toml = camera.to_toml()
    else:
        camera, camera_toml = LightField.read_camera(sources[0]), ""
        if camera is None:
            raise LfprocError(f"{sources[0]}: this light field carries no camera; give --camera CAM")
    if args.grid and to_decode:   # a grid of another camera: refused here, naming the camera file
        from ..grid import LensGrid
        from ..inputs import check_grid_fits_camera
        check_grid_fits_camera(camera, LensGrid.load(args.grid))
    if args.views:
        check_view_options(args, camera)
    settings = deconvolution_settings(args, camera, args.z_range_um) if args.deconvolve else None
    if not args.deconvolve and (args.a is not None or args.depth_range_mm is not None or args.distance_mm is not None
                                or args.z_range_um is not None):
        a_values = tuple(slice_parameters(camera, args.a, args.depth_range_mm, args.distance_mm, args.max_gap, args.integer,
                                          max_slices=args.max_slices, z_range=args.z_range_um,
                                          view_extent=aperture_extent(camera, args.aperture)))
    else:
        a_values = ()
    require_output_folder(args.outdir)
    white = _abs(white_image_for(to_decode, args.white, args.white_dir)) if to_decode else None
    if args.grid and not white:  # decode with the white image the grid file recorded (as lfproc refocus
        from ..grid import LensGrid  # does), and let its file stamp into every capture's fingerprint

        fit = LensGrid.load(args.grid).calibration
        recorded = fit.white_image if fit is not None else None
        white = os.path.abspath(recorded) if recorded and os.path.isfile(recorded) else None
    stems = unique_stems(sources)
    outdir = os.path.abspath(args.outdir)
    jobs = [batch.Job(src, stems[src], outdir, camera_toml, _abs(args.grid), white, a_values,
                      bool(args.views), args.format, args.interpolation, args.decode_interpolation, args.demosaic,
                      args.upsample, bool(args.mosaic), bool(args.gif), bool(args.inside_aperture), args.aperture,
                      _abs(args.dark), args.stack if a_values else None, _abs(args.camera),
                      white_is_white=args.white_is_white, deconvolve=settings)
            for src in sources]
    first_to_decode = next((job for job in jobs if not is_lightfield_file(job.source)), None)
    if not os.path.isdir(outdir) and first_to_decode is not None:
        # a first run: check the camera, white image and grid before anything is written (exit 2, nothing left)
        batch.decode_setup(first_to_decode)
    summed = _summed_views(camera, args.aperture, first_to_decode) if a_values else None
    from ..geometry import summed_view_extent
    if summed is not None and (args.depth_range_mm is not None or args.distance_mm is not None
                               or args.z_range_um is not None):
        # planned again for the DOF of the views the slices will really sum (those that carry light), as refocus does
        a_values = tuple(slice_parameters(camera, args.a, args.depth_range_mm, args.distance_mm, args.max_gap,
                                          args.integer, max_slices=args.max_slices, z_range=args.z_range_um,
                                          view_extent=summed_view_extent(summed)))
        jobs = [dataclasses.replace(job, refocus_a=a_values) for job in jobs]
    if a_values:   # the workers keep their warnings to themselves: the z-step advice is said here, once
        from ..api import check_z_step

        check_z_step(camera, a_values)
    try:
        os.makedirs(outdir, exist_ok=True)
    except OSError as exc:
        raise LfprocError(f"{args.outdir}: cannot create the output folder ({exc.strerror}); check the path") \
            from None
    with batch.lock_outdir(outdir) as stale_lock, _sigterm_as_interrupt():
        if stale_lock:
            print(f"lfproc batch: note: took over the lock of {stale_lock}, which is no longer running "
                  f"(interrupted or killed); resuming", file=sys.stderr)
        batch.remove_stale_partial_files(outdir)
        manifest = batch.Manifest(outdir, {
            "camera": _abs(args.camera), "calib": _abs(args.grid), "white": white,
            "refocus_a": list(a_values), "views": bool(args.views), "format": args.format,
            "interpolation": args.interpolation, "upsample": args.upsample, "mosaic": bool(args.mosaic),
            "gif": bool(args.gif), "inside_aperture": bool(args.inside_aperture), "aperture": args.aperture,
            "decode_interpolation": args.decode_interpolation, "demosaic": args.demosaic,
            "stack": args.stack, "scheduler": args.scheduler, **({"dark": _abs(args.dark)} if args.dark else {}),
            **({"deconvolve": settings} if settings else {})})
        return _process(args, jobs, manifest, camera, summed)


def _summed_views(camera, aperture, job):
    """The views the slices will sum: those the decoder delivers (from the batch's one decode setup), within
    ``--aperture``; None where that is every view (or no white image says which carry light)."""
    from .. import batch
    from ..geometry import aperture_views

    import numpy as np

    mask = None
    if job is not None:
        setup = batch.decode_setup(job)
        camera = setup.camera          # m̂ from the measured pitch where the camera file states none
        if setup.has_white:
            mask = np.asarray(setup.decoder_for((), "none").views_delivered, dtype=bool)
    if aperture is not None:
        keep = aperture_views(camera, aperture)
        mask = keep if mask is None else keep & mask
    return None if mask is None or mask.all() else mask


def _process(args, jobs, manifest, camera, summed=None) -> int:
    """Skip what is complete, run the rest, keep the manifest current; returns the exit status."""
    from tqdm import tqdm

    from .. import batch

    fingerprints = {job.source: job.fingerprint() for job in jobs}
    todo, counts, failures, warned = [], {"done": 0, "skipped": 0, "failed": 0}, [], []
    for job in jobs:
        if manifest.is_complete(job, fingerprints[job.source]):
            counts["skipped"] += 1
            manifest.record(job, batch.JobResult(job.source, "skipped"), fingerprints[job.source])
        else:
            todo.append(job)
    first_to_decode = next((job for job in todo if job.camera_toml), None)
    if first_to_decode is not None:
        # fail fast on a bad camera, white image or grid file, before any worker starts (exit status 2)
        note = batch.decode_setup(first_to_decode).m_hat_note
        if note:
            print(f"lfproc batch: {note}", file=sys.stderr)
    manifest.data.pop("operators", None)      # a record of this run's operators only (none when none are needed)
    operators = _shared_operators(todo[0], manifest) if todo and todo[0].deconvolve else None
    if jobs[0].refocus_a:
        describe_slices(camera, jobs[0].refocus_a, args.depth_range_mm, max_gap_mm=args.max_gap,
                        integer=args.integer, max_slices=args.max_slices, view_mask=summed)
    start = time.perf_counter()
    interrupted = False
    tqdm.monitor_interval = 0  # no monitor thread: signals reach the main thread's handler (batch._signals)
    try:
        with tqdm(total=len(todo), unit="capture", disable=None, file=sys.stderr, desc="lfproc batch") as bar:
            def on_result(job, result):
                # marked by the library: the manifest and stderr use the flags
                result = dataclasses.replace(result, error=result.error and command_words(result.error, "batch"),
                                             warnings=tuple(command_words(line, "batch") for line in result.warnings))
                if result.warnings:
                    warned.append((job.source, result.warnings))
                counts[result.status] += 1
                manifest.record(job, result, fingerprints[job.source])
                manifest.save_soon()
                if result.status == "failed":
                    failures.append((job.source, result.error))
                    bar.write(f"lfproc batch: failed: {result.error}", file=sys.stderr)
                bar.update(1)

            if not todo:
                pass
            elif args.scheduler:
                batch.run_dask(todo, args.scheduler, on_result, operators)
            else:
                # a deconvolving worker also holds the operators and the projections' matrices (512 MB budget)
                extra = 0.0 if operators is None else 2.0 * operators.kernels.nbytes + 512 * 2 ** 20
                workers = args.workers or batch.default_workers(todo[0].source, extra_bytes=extra)
                batch.run_local(todo, min(workers, len(todo)), on_result, operators=operators)
        # every task has ended: what a killed worker was writing is garbage now
        batch.remove_stale_partial_files(manifest.outdir)
    except KeyboardInterrupt:
        interrupted = True
        if not args.scheduler:  # the local workers have ended: their abandoned temporary files are garbage
            batch.remove_stale_partial_files(manifest.outdir)
    finally:
        summary = dict(counts, total=len(jobs), seconds=round(time.perf_counter() - start, 3),
                       interrupted=interrupted, warned=len(warned),
                       failed_captures=[{"source": s, "error": e} for s, e in failures])
        manifest.save(summary)
    print(format_summary(summary, manifest.path))
    if warned and not interrupted:     # interrupted: one line says so (the manifest has the warnings)
        print(warnings_summary(warned, counts["done"] + counts["failed"]), file=sys.stderr)
    if interrupted:
        left = len(jobs) - counts["done"] - counts["skipped"] - counts["failed"]
        print(f"lfproc batch: interrupted with {counts['done']} done, {counts['skipped']} skipped, "
              f"{counts['failed']} failed and {left} not done of {len(jobs)} captures (recorded in the manifest; "
              f"the captures not done left no output); rerun the same command to resume", file=sys.stderr)
        return 130
    return 2 if failures else 0


def _shared_operators(job, manifest):
    """The batch's deconvolution operators, built here once (or read from lfproc's cache, as lfproc deconvolve
    does) before any worker starts; the manifest records whether they were built and what they cost."""
    from tqdm import tqdm

    from .. import batch

    start, built = time.perf_counter(), [0]
    with tqdm(total=len(job.deconvolve["z_um"]), unit="plane", disable=None, file=sys.stderr,
              desc="lfproc batch: operators", leave=False) as bar:
        def progress(stage, done, total):
            built[0] = 1
            bar.update(1)

        operators = batch.shared_operators(job, progress)
    manifest.data["operators"] = {"built": built[0], "seconds": round(time.perf_counter() - start, 3),
                                  "megabytes": round(operators.kernels.nbytes / 1e6, 1)}
    return operators


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """SIGTERM (kill, a job scheduler's time limit) stops a batch like Ctrl-C: captures in progress
    abandoned (nothing of them written), those finished recorded, the manifest saved."""
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread (an embedding application): leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def format_summary(summary: dict, manifest_path: str) -> str:
    lines = [f"{'done':>8} {'skipped':>8} {'failed':>8} {'total':>8} {'seconds':>9}",
             f"{summary['done']:>8} {summary['skipped']:>8} {summary['failed']:>8} {summary['total']:>8} "
             f"{summary['seconds']:>9.1f}"]
    for item in summary["failed_captures"]:
        error = item["error"] or ""
        lines.append(f"failed: {error if error.startswith(item['source']) else item['source'] + ': ' + error}")
    lines.append(f"manifest: {manifest_path}")
    return "\n".join(lines)


def warnings_summary(warned: list, processed: int) -> str:
    """How many of the ``processed`` captures warned (their warnings are in the manifest) and each distinct warning once: the
    capture's own path in a message is left out of the comparison, so a warning every capture gives is one line."""
    distinct = {}
    for source, lines in warned:
        for line in lines:
            distinct.setdefault(line.replace(source, "CAPTURE"), [line, 0])[1] += 1
    text = [f"lfproc batch: {len(warned)} of {processed} captures processed warned (each capture's warnings are in "
            f"the manifest):"]
    for line, count in distinct.values():
        text.append(f"  {line}" + (f" (and {count - 1} more capture(s) alike)" if count > 1 else ""))
    return "\n".join(text)


def _without_pictures(inputs, sources):
    """Processed Lytro pictures named on the command line are refused (one line); those found in a folder are
    skipped with a warning (a Lytro library holds raw files and pictures side by side)."""
    import warnings

    from ..io import is_picture_file, refuse_pictures

    refuse_pictures([path for path in inputs if os.path.isfile(path)])
    pictures = [path for path in sources if path not in inputs and is_picture_file(path)]
    kept = [path for path in sources if path not in pictures]
    if not kept:
        raise LfprocError(f"{', '.join(inputs)}: only processed Lytro pictures here, no raw light field; use "
                          f"lfproc export for them")
    for path in pictures:
        warnings.warn(f"{path}: skipped, a processed Lytro picture (no raw light field); use lfproc export for it")
    return kept
