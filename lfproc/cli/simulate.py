"""``lfproc simulate``: render a synthetic raw capture, its white image and the ground truth from a scene file."""

from __future__ import annotations

import os

OUTPUT_NAMES = ("capture.png", "white.png", "camera.toml", "ground_truth.npz", "ground_truth.json")


def register(sub) -> None:
    p = sub.add_parser("simulate", help="render a synthetic SPC raw capture, white image and ground truth",
                       description="Render the scene file SCENE.toml through the paraxial "
                                   "SPC model (a microscope's [[bead]]s through its ray-traced objective) and write "
                                   "DIR/capture.png and DIR/white.png (16-bit), "
                                   "DIR/camera.toml, DIR/ground_truth.npz (ideal_views, ideal_weight, "
                                   "plane_label, depth_mm) and DIR/ground_truth.json (the micro image centre "
                                   "grid, planes with their refocus parameter a, render options; with a finite "
                                   "exit pupil also the lens grid).")
    p.add_argument("scene", metavar="SCENE.toml",
                   help="scene file: commented examples ship with lfproc as sample/scene.toml and, for a "
                        "microscope's beads, microscope/beads.toml (lfproc info --samples prints their folder)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--seed", type=int, default=None, help="override [render] seed")
    p.set_defaults(func=run)


def run(args) -> int:
    import sys
    import time
    from dataclasses import replace

    from tqdm import tqdm

    from ..errors import LfprocError
    from ..simulate import load_scene_file, render
    from .capture_loop import require_output_folder

    scene_file = load_scene_file(args.scene)
    options = scene_file.options
    if args.seed is not None:
        if args.seed < 0:
            raise LfprocError(f"--seed must be an integer >= 0, got {args.seed}")
        options = replace(options, seed=args.seed)
    require_output_folder(args.output)  # the same check as every command: before any work
    start = time.perf_counter()
    if scene_file.beads:
        return _run_beads(args.output, scene_file, options, start)
    # the same bar as refocus and views: on stderr, only on a terminal; here in percent of the traced rays
    with tqdm(total=100, unit="%", disable=None, file=sys.stderr, desc="lfproc simulate",
              bar_format="{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]") as bar:
        shown = []

        def progress(fraction: float, stage: str) -> None:
            new_stage = not shown or shown[-1] != stage
            if new_stage:
                shown.append(stage)
                bar.set_description_str(f"lfproc simulate ({stage})", refresh=False)
            bar.update(round(100 * fraction) - bar.n)
            if new_stage:
                bar.refresh()  # each stage is shown at least once, however fast

        capture = render(scene_file.camera, scene_file.scene, options.sensor_shape, **options.render_kwargs(),
                         progress=progress)
        bar.set_description_str("lfproc simulate (writing)")
        write_outputs(args.output, capture, scene_file, options)
    print(summary(args.output, capture, time.perf_counter() - start))
    return 0


def _run_beads(folder: str, scene_file, options, start: float) -> int:
    """A microscope scene: its beads and white image through the ray-traced objective, the camera file and the
    beads' positions (DIR/ground_truth.json); no ground_truth.npz (no views to compare with)."""
    import time

    from ..atomic import write_json_atomic, write_text_atomic
    from ..io import write_image
    from ..simulate import render_microscope_capture

    camera = scene_file.camera
    capture, white = render_microscope_capture(
        camera, scene_file.beads, options.sensor_shape, background=scene_file.scene.background[0],
        pixel_samples=options.pixel_samples, aperture_samples=options.aperture_samples,
        shot_noise_photons=options.shot_noise_photons, read_noise_dn=options.read_noise_dn,
        exposure=options.exposure, seed=options.seed)
    os.makedirs(folder, exist_ok=True)
    write_image(os.path.join(folder, "capture.png"), capture)
    write_image(os.path.join(folder, "white.png"), white)
    write_text_atomic(os.path.join(folder, "camera.toml"), camera.to_toml())
    write_json_atomic(os.path.join(folder, "ground_truth.json"), {
        "format": "lfproc-simulation-1", "kind": "microscope beads",
        "scene": os.path.abspath(scene_file.source) if scene_file.source else "",
        "sensor_shape": [int(v) for v in capture.shape],
        "beads": [{"x_um": b.x_um, "y_um": b.y_um, "z_um": b.z_um, "radius_um": b.radius_um,
                   "brightness": b.brightness} for b in scene_file.beads],
        "background": float(scene_file.scene.background[0]), "render": options.to_json_dict()})
    height, width = capture.shape
    print("\n".join([
        f"lfproc simulate: rendered {height}x{width} px of a light-field microscope, {len(scene_file.beads)} "
        f"bead(s) in {time.perf_counter() - start:.1f} s",
        f"  {os.path.join(folder, 'capture.png')}: the raw capture (16-bit)",
        f"  {os.path.join(folder, 'white.png')}: its white image (16-bit)",
        f"  {os.path.join(folder, 'camera.toml')}: the camera file",
        f"  {os.path.join(folder, 'ground_truth.json')}: the beads' positions (um in the sample), render options"]))
    return 0


def summary(folder: str, capture, seconds: float) -> str:
    """What ``lfproc simulate`` rendered and wrote: one line per file."""
    grid, camera = capture.grid, capture.camera
    height, width = capture.raw.shape
    sensor = "mono" if camera.cfa == "none" else f"{camera.cfa} mosaic"
    pupil = "telecentric" if camera.telecentric else f"exit pupil {camera.main_optics.exit_pupil_distance_mm:g} mm"
    arrays = "plane_label, depth_mm"
    if capture.ideal_views is not None:
        arrays += ", ideal_views " + "x".join(str(n) for n in capture.ideal_views.shape) + ", ideal_weight"
    grids = "micro image grid" + ("" if camera.telecentric else " and lens grid")
    lines = [f"lfproc simulate: rendered {height}x{width} px ({sensor}, {pupil}), {grid.rows}x{grid.cols} "
             f"{grid.kind} micro images of {grid.pitch_px:.4f} px, {len(capture.planes)} plane(s) in {seconds:.1f} s",
             f"  {os.path.join(folder, 'capture.png')}: the raw capture (16-bit)",
             f"  {os.path.join(folder, 'white.png')}: its white image (16-bit)",
             f"  {os.path.join(folder, 'camera.toml')}: the camera file",
             f"  {os.path.join(folder, 'ground_truth.npz')}: {arrays}",
             f"  {os.path.join(folder, 'ground_truth.json')}: {grids}, planes with distance and refocus a, "
             f"render options"]
    return "\n".join(lines)


def write_outputs(folder: str, capture, scene_file, options) -> None:
    """Write the five outputs of ``lfproc simulate`` into ``folder``, each atomically."""
    import numpy as np

    from ..atomic import atomic_path, write_json_atomic, write_text_atomic
    from ..geometry import refocus_parameter
    from ..io import write_image
    from ..simulate import micro_image_scale

    write_image(os.path.join(folder, "capture.png"), capture.raw)   # uint16: written exactly, 16-bit PNG
    write_image(os.path.join(folder, "white.png"), capture.white)
    write_text_atomic(os.path.join(folder, "camera.toml"), capture.camera.to_toml())
    arrays = {"plane_label": capture.plane_label, "depth_mm": capture.depth_mm}
    if capture.ideal_views is not None:
        arrays.update(ideal_views=capture.ideal_views, ideal_weight=capture.ideal_weight)
    with atomic_path(os.path.join(folder, "ground_truth.npz")) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)
    planes = []
    for index, plane in enumerate(capture.planes):
        record = plane.describe()
        record["index"] = index
        record["refocus_a"] = float(refocus_parameter(capture.camera, plane.distance_mm))
        planes.append(record)
    camera = capture.camera
    truth = {
        "format": "lfproc-simulation-1",
        "scene": os.path.abspath(scene_file.source) if scene_file.source else "",
        "sensor_shape": [int(v) for v in capture.raw.shape],
        "optical_axis_xy_px": [(capture.raw.shape[1] - 1) / 2.0, (capture.raw.shape[0] - 1) / 2.0],
        "grid": capture.grid.to_json_dict(),
        "planes": planes,
        "background": list(scene_file.scene.background),
        "rim_radius_mm": capture.rim_radius_mm,
        "render": options.to_json_dict(),
        "micro_image_px": camera.m_hat,
        "effective_pixel_pitch_mm": camera.effective_pixel_pitch_mm,
        "ideal_views": "ground_truth.npz: ideal_views (m, m, rows, cols, C), ideal_weight (m, m, rows, cols), "
                       "plane_label (rows, cols; -1 = background)",
    }
    if not camera.telecentric:  # absent when telecentric: "grid" is then also the lens grid
        truth["exit_pupil_distance_mm"] = camera.main_optics.exit_pupil_distance_mm
        truth["micro_image_scale"] = micro_image_scale(camera)
        truth["lens_grid"] = capture.lens_grid.to_json_dict()
    write_json_atomic(os.path.join(folder, "ground_truth.json"), truth)
