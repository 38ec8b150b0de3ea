"""The files of ``lfproc depth`` for one capture (contract, ARCHITECTURE.md), each with its sidecar.

* ``STEM_depth.tif`` — float32, one channel, in the camera's object space (:attr:`DepthMap.space`): mm from
  the sensor (``inf`` = infinity), or µm from a microscope's native object plane; NaN = unknown;
* ``STEM_depth_confidence.tif`` — float32, 0–1;
* ``STEM_allfocus.tif`` — float32 linear, the light field's channels;
* ``STEM_depth_preview.png`` — colour-mapped depth with a legend in metres (µm for a microscope);
* ``STEM_depth_points.ply`` — the point cloud (optional; distances from the sensor only).

Every image embeds the same metadata as its sidecar ``NAME.json`` (``source``, ``unit``, ``method``,
the searched range …). Everything is written atomically; a failure leaves no partial file.
"""

from __future__ import annotations

import os

import numpy as np

#: output name suffixes
DEPTH, CONFIDENCE, ALLFOCUS, PREVIEW, POINTS = ("_depth.tif", "_depth_confidence.tif", "_allfocus.tif",
                                                "_depth_preview.png", "_depth_points.ply")

#: what ``STEM_depth.tif`` holds, by the position key of the two built-in object spaces (other spaces:
#: :func:`_depth_content`)
DEPTH_CONTENT = {"distance_mm": "distance from the sensor (Eq. 21); NaN = unknown, inf = infinity",
                 "z_um": "depth from the native object plane, positive towards the objective (z_um of the sharpest "
                         "slice); NaN = unknown"}

#: the preview's legend unit and its sidecar's ``content``, by the unit of the depth map's object space
PREVIEW_LEGEND = {"mm": ("m", "colour-mapped depth (viridis: yellow near, dark purple far, grey unknown, black no "
                              "light), legend in metres"),
                  "um": ("um", "colour-mapped depth (viridis: yellow nearest the objective, dark purple farthest, grey "
                               "unknown, black no light), legend in µm")}


def write_depth_outputs(outdir, stem: str, depth_map, *, point_cloud: bool = True) -> dict:
    """Write the depth outputs of one depth map (:meth:`DepthMap.save`), each with the map's tags
    (:meth:`DepthMap.tags`) in its metadata and sidecar.

    Parameters
    ----------
    outdir : str or path
        Output folder (created if needed).
    stem : str
        File name prefix, e.g. the capture's name.
    depth_map : DepthMap
        The estimate, with the light field it was made from (its camera gives the geometry, its grid the
        point cloud).
    point_cloud : bool
        Also write ``STEM_depth_points.ply`` (where the optics place each lens's chief ray).

    Returns
    -------
    dict
        ``{"depth", "confidence", "allfocus", "preview"[, "points"]}`` → path written.
    """
    from ..io import write_image, write_sidecar
    from ._pointcloud import point_cloud as make_points
    from ._pointcloud import write_ply
    from ._preview import write_preview

    lf = depth_map.light_field
    camera = getattr(lf, "camera", None)
    source = depth_map.source
    common = depth_map.tags()
    outdir = os.fspath(outdir)
    os.makedirs(outdir, exist_ok=True)
    space = depth_map.space
    known = ~np.isnan(depth_map.depth)
    paths = {}
    meta = dict(common, unit=space.unit, content=_depth_content(space),
                known_fraction=float(known.mean()) if known.size else 0.0)
    sampling = None if camera is None else camera.main_optics.lateral_sampling_um(camera)
    if sampling is not None:   # the lenses' spacing in the object: one lateral sampling for every depth
        meta["lateral_sampling_um"] = sampling
    paths["depth"] = _write_float(os.path.join(outdir, stem + DEPTH), depth_map.depth, meta)
    meta = dict(common, unit="1", content="confidence of the depth, 0 (nothing known) to 1")
    paths["confidence"] = _write_float(os.path.join(outdir, stem + CONFIDENCE), depth_map.confidence, meta)
    meta = dict(common, unit="linear radiance", content="all-in-focus image: each lens from the slice sharp at its depth")
    path = os.path.join(outdir, stem + ALLFOCUS)
    write_image(path, depth_map.allfocus, meta, "tiff")
    write_sidecar(path, meta)
    paths["allfocus"] = path
    distances = space.toward_optics < 0     # distances reach infinity: an inverse colour scale, legend in metres
    unit, content = PREVIEW_LEGEND["mm" if distances else "um"]
    meta = dict(common, unit=unit, content=content)
    path = os.path.join(outdir, stem + PREVIEW)
    unlit = None if depth_map.lit is None else ~depth_map.lit
    if distances:
        write_preview(path, depth_map.depth * (1.0 / space.per_mm), None, unlit)
    else:
        write_preview(path, None, depth_map.depth * (1000.0 / space.per_mm), unlit)
    write_sidecar(path, meta)
    paths["preview"] = path
    points = None
    if point_cloud and camera is not None:   # x, y from each lens's chief ray, where the optics place them
        points, rgb = make_points(camera, getattr(lf, "grid", None), depth_map.depth, depth_map.allfocus)
    if points is not None:
        path = os.path.join(outdir, stem + POINTS)
        meta = dict(common, unit="mm", content="x, y: object-space position from the optical axis; z: distance from "
                    "the sensor (central view's chief ray through each lens, Eqs. 13-21)", points=len(points))
        write_ply(path, points, rgb, comment=f"lfproc depth point cloud, mm; source {source}")
        write_sidecar(path, meta)
        paths["points"] = path
    return paths


def _depth_content(space) -> str:
    """What ``STEM_depth.tif`` holds: the built-in spaces' words, else the space's own."""
    reach = ", inf = infinity" if space.toward_optics < 0 else ""
    return DEPTH_CONTENT.get(space.position_key,
                             f"{space.position_key} of the sharpest slice, {space.symbol} {space.origin}; NaN = "
                             f"unknown{reach}")


def summary_line(depth_map) -> str:
    """One line for a terminal: how much is known (and of the lenses light reached), and the range of the known
    distances (metres; µm for a microscope)."""
    space = depth_map.space
    depth = depth_map.depth
    known = ~np.isnan(depth)
    text = f"depth known at {known.mean():.0%} of {depth.size} lenses"
    lit = depth_map.lit
    if lit is not None and not lit.all():
        text += f" ({known[lit].mean() if lit.any() else 0.0:.0%} of the {lit.mean():.0%} that light reached)"
    if space.toward_optics > 0:   # signed depths, linear: no infinity
        if known.any():
            lo, hi = (float(v) for v in np.percentile(depth[known], [1, 99]))
            text += f", {space.letter} {lo:.4g} to {hi:.4g} {space.symbol} {space.origin.split(',')[0]} (1st to 99th " \
                    f"percentile)"
        return text
    finite = depth[np.isfinite(depth)]
    if finite.size:
        near, far = (float(v) / (1000.0 / space.per_mm) for v in np.percentile(finite, [1, 99]))
        text += f", {near:.3g} to {far:.3g} m (1st to 99th percentile)"
    if np.isinf(depth).any():
        text += ", some at infinity"
    return text


def _write_float(path: str, image: np.ndarray, metadata: dict) -> str:
    """A float32 single-channel TIFF that may hold NaN (unknown) and inf, with ``metadata`` embedded and its
    sidecar."""
    from ..io import write_image, write_sidecar

    write_image(path, np.asarray(image, dtype=np.float32), metadata, "tiff", allow_nonfinite=True)
    write_sidecar(path, metadata)
    return path
