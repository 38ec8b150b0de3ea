"""``lfproc demo``: the whole pipeline on the bundled sample, written to ``./lfproc-demo/``.

Geometry of the sample camera → grid calibration from the white image → decoding into a light field
→ a refocus stack covering the sample's depth range (plus a labelled animation) → the viewpoint mosaic
(plus an 8-bit preview) and a view animation → the depth map (``lfproc-demo/depth/``, with its preview
in metres) → the browser viewer (``lfproc-demo/viewer/index.html``).
The summary checks the refocused slices against the sample's known plane distances.
"""

from __future__ import annotations

import json
import time
import warnings
from pathlib import Path

from ..errors import LfprocError, LfprocWarning
from .capture_loop import require_output_folder

SAMPLE_FILES = ("capture.png", "white.png", "camera.toml", "ground_truth.json")


def default_sample_dir() -> Path:
    """The bundled sample, shipped inside the package (``lfproc/samples/sample``; ``samples/`` in a source
    checkout links there), so the demo runs from a wheel as from a checkout."""
    return Path(__file__).resolve().parents[1] / "samples" / "sample"


def register(sub) -> None:
    p = sub.add_parser("demo", help="run the whole pipeline on the bundled sample",
                       description="Calibrate, decode, refocus across the depth range and extract the views of the "
                                   "bundled sample capture; writes into ./lfproc-demo/ and prints what it wrote.")
    p.add_argument("-o", "--outdir", default="lfproc-demo", help="output folder (default ./lfproc-demo)")
    p.add_argument("--sample", default=None, help="sample folder (default: the sample bundled with lfproc)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import geometry
    from ..camera import Camera
    from ..api import calibrate_white, depth_map, focal_stack, read_light_field
    from ..outputs import shown_views, write_mosaic_preview, write_slice_gif, write_view_gif, write_view_mosaic
    from ..viewer import build_page, calibration_summary

    sample = Path(args.sample) if args.sample else default_sample_dir()
    missing = [name for name in SAMPLE_FILES if not (sample / name).is_file()]
    if missing:
        raise LfprocError(f"{sample}: the sample is missing {', '.join(missing)}; reinstall lfproc, or regenerate it "
                          f"with python scripts/make_samples.py in a source checkout")
    require_output_folder(args.outdir)   # a read-only folder fails here, in one line, before any work
    out = Path(args.outdir)
    t0 = time.perf_counter()

    def step(text):
        print(text, flush=True)

    camera = Camera.from_toml(sample / "camera.toml")
    truth = json.loads((sample / "ground_truth.json").read_text())
    distances = sorted(p["distance_mm"] for p in truth["planes"])
    step(f"camera {camera.name}: {camera.pitch_px:.3f} px per lens -> {camera.m_hat}x{camera.m_hat} views, "
         f"baseline {geometry.baseline_mm(camera):.3f} mm")

    grid = calibrate_white(sample / "white.png", camera)
    out.mkdir(parents=True, exist_ok=True)
    grid_path = out / "grid.json"
    grid.save(grid_path)      # what `lfproc calibrate` writes
    step(f"calibrated {grid.rows}x{grid.cols} {grid.kind} lenses: pitch {grid.pitch_px:.4f} px, rotation "
         f"{grid.rotation_deg:.4f} deg, residual {grid.residual_rms_px:.4f} px -> {grid_path}")

    lf = read_light_field(str(sample / "capture.png"), camera, white=str(sample / "white.png"), grid=grid, cache=True)
    lf_path = out / "sample.lfp.npz"
    lf.save(lf_path)
    m, _, ny, nx, ch = lf.views.shape
    step(f"decoded {m}x{m} views of {ny}x{nx} lenses x {ch} channels -> {lf_path}")

    near, far = distances[0] * 0.97, distances[-1] * 1.03
    extent = None if lf.view_mask is None else geometry.summed_view_extent(lf.view_mask)   # DOF of the views summed
    a_values = [float(a) for a in geometry.plan_slices(camera, near, far, view_extent=extent)]
    with warnings.catch_warnings():      # the summary below says which planes each slice holds sharply
        warnings.simplefilter("ignore", LfprocWarning)
        stack = focal_stack(lf, a=a_values)     # as `lfproc refocus` writes them
    source = stack.source
    refocus_dir = out / "refocus"
    paths = stack.save(str(refocus_dir), "sample")
    gif = write_slice_gif(str(out), "sample", stack.images[::-1], camera, a_values[::-1],   # near to far, labelled
                          view_mask=lf.view_mask)
    geo = geometry.slice_geometry(camera, a_values, extent)     # the slices' own DOFs, as their sidecars say
    step(f"refocused {len(a_values)} slices covering {min(geo.near_mm):.0f}..{max(geo.far_mm):.0f} mm -> "
         f"{refocus_dir}/ (+ sidecars), {gif}")
    for d in distances:
        hits = [f"a={a:+.3f} [{lo:.0f}, {hi:.0f}] mm" for a, lo, hi in zip(a_values, geo.near_mm, geo.far_mm)
                if lo <= d <= hi]
        step(f"  plane at {d:.0f} mm is in focus in slice {', '.join(hits) or '(none)'}")

    inside = geometry.views_inside_aperture(camera)
    keep = shown_views(lf, inside_aperture=True).keep   # the views with light inside the main lens stop
    mosaic_path = write_view_mosaic(str(out), "sample", source, camera, lf.views, "tiff", keep,
                                    provenance=stack.provenance)
    preview = write_mosaic_preview(str(out), "sample", lf.views, keep, camera=camera)
    view_gif = write_view_gif(str(out), "sample", lf.views, keep, camera)
    step(f"views: {int(inside.sum())} of {m * m} inside the aperture, {int(keep.sum())} decoded with light; mosaic "
         f"{mosaic_path} (preview {preview}), animation {view_gif}")
    depth = depth_map(lf)   # the whole default search (from infinity nearer): the planes sit near near..far's ends
    written = depth.save(str(out / "depth"), "sample")
    step(f"depth: {depth.summary()} -> {written['depth']} (preview {written['preview']})")
    page = build_page(lf, str(out / "viewer"), source=source, stem="sample", a_values=a_values,
                      calibration=calibration_summary(grid, str((sample / "white.png").resolve())),
                      depth_map=depth, focal_stack=stack)
    step(f"viewer: {Path(page).resolve()}")
    step("  open it in a browser: click to refocus and read distances, drag to move the viewpoint")
    step(f"done in {time.perf_counter() - t0:.1f} s: {len(paths)} slices, 1 mosaic, 2 animations, 1 depth map, 1 viewer "
         f"in {out}/")
    return 0
