"""``lfproc batch``: refocus and extract views from many captures, locally or on a Dask cluster; resumable."""

from __future__ import annotations

import os
import sys
import time

from ..errors import LfprocError


def register(sub) -> None:
    p = sub.add_parser("batch", help="process folders of captures in parallel (local or Dask), resumable",
                       description="Process many captures: inputs are files, folders or glob patterns. A manifest "
                                   "in OUTDIR records each capture; a rerun skips completed captures whose "
                                   "parameters are unchanged. Failures are recorded and the rest complete.")
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="capture files, folders or glob patterns")
    p.add_argument("--camera", required=True, metavar="CAM")
    p.add_argument("--calib", metavar="GRID.json")
    p.add_argument("--white", metavar="WHITE")
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR")
    which = p.add_mutually_exclusive_group()
    which.add_argument("--refocus", metavar="LIST", help="refocus parameters a (numbers, START:STOP[:STEP])")
    which.add_argument("--depth-range", metavar="NEAR_MM:FAR_MM", help="the fewest slices covering this range")
    p.add_argument("--views", action="store_true", help="also write every viewpoint image")
    p.add_argument("--format", default="tiff", choices=("tiff", "png16", "jpeg", "exr"))
    p.add_argument("--interpolation", default="linear", choices=("nearest", "linear", "cubic"))
    p.add_argument("--decode-interpolation", default="linear", choices=("nearest", "linear", "cubic", "lanczos"))
    p.add_argument("--demosaic", default="fast", choices=("fast", "careful"))
    p.add_argument("--workers", type=int, metavar="N", help="local processes (default: from cores and memory)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler, e.g. tcp://host:8786")
    p.set_defaults(func=run)


def _abs(path):
    return None if path is None else os.path.abspath(path)


def run(args) -> int:
    from tqdm import tqdm

    from .. import batch
    from ..camera import Camera
    from ..pipeline import unique_stems
    from .common import parse_depth_range, parse_number_list

    camera = Camera.from_toml(args.camera)
    if not args.calib and not args.white:
        raise LfprocError("give --white WHITE (a white image) or --calib GRID.json (from lfproc calibrate)")
    for path, flag in ((args.calib, "--calib"), (args.white, "--white")):
        if path is not None and not os.path.isfile(path):
            raise LfprocError(f"{path}: {flag} file not found; check the path")
    if args.refocus is None and args.depth_range is None and not args.views:
        raise LfprocError("nothing to do: give --refocus LIST, --depth-range NEAR:FAR and/or --views")
    if args.workers is not None and args.workers < 1:
        raise LfprocError(f"--workers must be >= 1, got {args.workers}")
    if args.refocus is not None:
        a_values = tuple(parse_number_list(args.refocus, "--refocus"))
    elif args.depth_range is not None:
        from ..geometry import plan_slices
        a_values = tuple(float(a) for a in plan_slices(camera, *parse_depth_range(args.depth_range)))
    else:
        a_values = ()
    sources = batch.expand_inputs(args.inputs)
    stems = unique_stems(sources)
    outdir = os.path.abspath(args.outdir)
    with open(args.camera, encoding="utf-8") as fh:
        camera_toml = fh.read()
    jobs = [batch.Job(src, stems[src], outdir, camera_toml, _abs(args.calib), _abs(args.white), a_values,
                      bool(args.views), args.format, args.interpolation, args.decode_interpolation, args.demosaic)
            for src in sources]
    os.makedirs(outdir, exist_ok=True)
    manifest = batch.Manifest(outdir, {"camera": os.path.abspath(args.camera), "calib": _abs(args.calib),
                                       "white": _abs(args.white), "refocus_a": list(a_values), "views": args.views,
                                       "format": args.format})
    fingerprints = {job.source: job.fingerprint() for job in jobs}
    todo, counts = [], {"done": 0, "skipped": 0, "failed": 0}
    for job in jobs:
        if batch.is_complete(manifest.entry(job.source), fingerprints[job.source]):
            counts["skipped"] += 1
            manifest.record(batch.JobResult(job.source, "skipped"), fingerprints[job.source])
        else:
            todo.append(job)
    failures = []
    start = time.perf_counter()
    with tqdm(total=len(todo), unit="capture", disable=None, file=sys.stderr, desc="lfproc batch") as bar:
        def on_result(job, result):
            counts[result.status] += 1
            manifest.record(result, fingerprints[job.source])
            if result.status == "failed":
                failures.append((job.source, result.error))
                bar.write(f"lfproc batch: failed: {result.error}")
            bar.update(1)

        if not todo:
            pass
        elif args.scheduler:
            batch.run_dask(todo, args.scheduler, on_result)
        else:
            workers = args.workers or batch.default_workers(todo[0].source, camera)
            batch.run_local(todo, min(workers, len(todo)), on_result)
    elapsed = time.perf_counter() - start
    summary = dict(counts, total=len(jobs), seconds=round(elapsed, 3),
                   failed_captures=[{"source": s, "error": e} for s, e in failures])
    manifest.save(summary)
    print(format_summary(summary, manifest.path))
    return 2 if failures else 0


def format_summary(summary: dict, manifest_path: str) -> str:
    lines = [f"{'done':>8} {'skipped':>8} {'failed':>8} {'total':>8} {'seconds':>9}",
             f"{summary['done']:>8} {summary['skipped']:>8} {summary['failed']:>8} {summary['total']:>8} "
             f"{summary['seconds']:>9.1f}"]
    for item in summary["failed_captures"]:
        lines.append(f"failed: {item['source']}: {item['error']}")
    lines.append(f"manifest: {manifest_path}")
    return "\n".join(lines)
