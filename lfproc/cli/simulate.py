"""``lfproc simulate``: render a synthetic raw capture, its white image and the ground truth from a scene file."""

from __future__ import annotations

import os

OUTPUT_NAMES = ("capture.png", "white.png", "camera.toml", "ground_truth.npz", "ground_truth.json")


def register(sub) -> None:
    p = sub.add_parser("simulate", help="render a synthetic SPC raw capture, white image and ground truth",
                       description="Render the scene file SCENE.toml (docs/scene-format.md) through the paraxial "
                                   "SPC model and write DIR/capture.png and DIR/white.png (16-bit), "
                                   "DIR/camera.toml, DIR/ground_truth.npz (ideal_views, ideal_weight, "
                                   "plane_label, depth_mm) and DIR/ground_truth.json (lens grid, planes with their refocus "
                                   "parameter a, render options).")
    p.add_argument("scene", metavar="SCENE.toml", help="scene file")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--seed", type=int, default=None, help="override [render] seed")
    p.set_defaults(func=run)


def run(args) -> int:
    from dataclasses import replace

    from ..errors import LfprocError
    from ..scene import load_scene_file
    from ..simulate import render

    scene_file = load_scene_file(args.scene)
    options = scene_file.options
    if args.seed is not None:
        if args.seed < 0:
            raise LfprocError(f"--seed must be an integer >= 0, got {args.seed}")
        options = replace(options, seed=args.seed)
    if os.path.exists(args.output) and not os.path.isdir(args.output):
        raise LfprocError(f"{args.output}: exists and is not a folder; give a folder for -o")
    capture = render(scene_file.camera, scene_file.scene, options.sensor_shape, **options.render_kwargs())
    write_outputs(args.output, capture, scene_file, options)
    grid = capture.grid
    print(f"wrote {', '.join(OUTPUT_NAMES)} to {args.output}: {options.height_px}x{options.width_px} px, "
          f"{grid.rows}x{grid.cols} {grid.kind} lenses of {grid.pitch_px:.4f} px, "
          f"{len(capture.planes)} plane(s)")
    return 0


def write_outputs(folder: str, capture, scene_file, options) -> None:
    """Write the five outputs of ``lfproc simulate`` into ``folder``, each atomically."""
    import numpy as np

    from ..atomic import atomic_path, write_json_atomic, write_text_atomic
    from ..geometry import refocus_parameter
    from ..io import write_image

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
    write_json_atomic(os.path.join(folder, "ground_truth.json"), truth)
