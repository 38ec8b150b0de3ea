"""A 3-D point cloud of the depth map (binary PLY): one point per lens of known distance.

The central view's chief ray through lens j leaves the micro lens at its height s_j with slope
m = −s_j/d_A towards the exit pupil centre (0 when the exit pupil is at infinity, the paper's case:
Eqs. 13–16 with Δu = 0). It reaches the main lens at U = s_j + m·b_U (Eq. 16), passes the front focal
plane at F = m·f_U (Eq. 17), so its object-side slope is q = (F − U)/f_U (Eq. 18) and at z from the main
lens's principal plane H1U it is at height U + q·z (Eq. 19). A surface at distance d from the sensor
lies at z = d − L (L: sensor to H1U), so the point is

    x = U_x + q_x·z,  y = U_y + q_y·z,  z_point = d

in mm, x along the sensor's columns and y along its rows (object space is inverted: lenses right of
the axis see points to the left), measured from the optical axis, which is taken through the centre of
the lens grid. With a finite exit pupil the decoded grid holds micro image centres, which sit
(d_A + f_s)/d_A farther out than their lenses; the lens heights are scaled back by that.
"""

from __future__ import annotations

import numpy as np


def lens_heights_mm(camera, grid, shape) -> tuple[np.ndarray, np.ndarray]:
    """Lens centre heights (s_y, s_x) in mm from the centre of the lens grid, ``shape`` = (Ny, Nx).

    With the light field's :class:`~lfproc.grid.LensGrid` of that shape, its lens positions (hexagonal
    rows offset, rotation included); otherwise a rectangular lattice of the micro lens pitch.
    """
    ny, nx = shape
    if grid is not None and (grid.rows, grid.cols) == (ny, nx):
        rr, qq = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
        xy = np.asarray(grid.lens_xy(rr, qq), dtype=np.float64) * camera.pixel_pitch_mm
        xy -= xy.reshape(-1, 2).mean(axis=0)
        return xy[..., 1], xy[..., 0]
    p = camera.mla_pitch_mm
    sy = (np.arange(ny) - (ny - 1) / 2.0)[:, None] * p * np.ones((1, nx))
    sx = (np.arange(nx) - (nx - 1) / 2.0)[None, :] * p * np.ones((ny, 1))
    return sy, sx


def point_cloud(camera, grid, distance_mm: np.ndarray, colours: np.ndarray | None = None):
    """``(N, 3)`` float32 points (x, y, z in mm, module docstring) of the finite distances, and their
    ``(N, 3)`` uint8 colours (from ``colours``, linear, sRGB-encoded); ``(None, None)`` where the optics place no
    chief rays (:func:`lfproc.geometry.chief_ray_heights`: a main lens's own geometry)."""
    from .. import geometry
    from ..io import srgb_encode

    sy, sx = lens_heights_mm(camera, grid, distance_mm.shape)
    if grid is not None:       # the grid is the micro image centres: back to the lenses
        sy, sx = sy / camera.micro_image_scale, sx / camera.micro_image_scale
    keep = np.isfinite(distance_mm)
    d = distance_mm[keep].astype(np.float64)
    heights = geometry.chief_ray_heights(camera, np.stack([sx[keep], sy[keep]]), d)
    if heights is None:
        return None, None
    points = np.stack([heights[0], heights[1], d], axis=1).astype(np.float32)
    rgb = None
    if colours is not None:
        c = colours[keep]
        c = np.repeat(c[:, :1], 3, axis=1) if c.shape[1] == 1 else c[:, :3]
        scale = float(np.percentile(colours, 99.5)) if colours.size else 1.0
        rgb = np.round(srgb_encode(c / (scale if scale > 0 else 1.0)) * 255.0).astype(np.uint8)
    return points, rgb


def write_ply(path: str, points: np.ndarray, rgb: np.ndarray | None = None, comment: str = "") -> None:
    """Binary little-endian PLY of float x, y, z (and uchar red, green, blue), written atomically."""
    from ..atomic import atomic_path
    from ..errors import LfprocError

    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    if rgb is not None:
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    record = np.zeros(len(points), dtype=fields)
    for i, name in enumerate("xyz"):
        record[name] = points[:, i]
    if rgb is not None:
        for i, name in enumerate(("red", "green", "blue")):
            record[name] = rgb[:, i]
    header = ["ply", "format binary_little_endian 1.0"]
    header += [f"comment {line}" for line in comment.splitlines() if line]
    header += [f"element vertex {len(points)}", "property float x", "property float y", "property float z"]
    if rgb is not None:
        header += ["property uchar red", "property uchar green", "property uchar blue"]
    header.append("end_header")
    try:
        with atomic_path(path, suffix=".ply") as tmp, open(tmp, "wb") as fh:
            fh.write(("\n".join(header) + "\n").encode("ascii", errors="replace"))
            fh.write(record.tobytes())
    except OSError as exc:
        raise LfprocError(f"{path}: cannot write ({exc.strerror or exc}); check the folder and permissions") from None
