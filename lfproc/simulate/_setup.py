"""Everything about the optics and sampling that does not depend on the scene (pure numpy).

The simulated lattices (:func:`default_grid` of the micro image centres, :func:`lens_grid_of` of
the lenses), the main lens rim (:func:`auto_rim_radius_mm`), the stratified sub-samples over a
pixel and over a micro lens aperture, and :class:`_Setup`, which bundles them for the kernels.

Exit pupil. With the exit pupil d_A in front of the micro lens array (the main lens's ``exit_pupil_distance_mm``),
the chief ray of the lens at height s comes from the pupil's centre and meets the sensor at
s·(d_A + f_s)/d_A: the micro image centres form the lens lattice scaled by that factor about the
optical axis (Hahne et al. 2018; :func:`micro_image_scale`). Telecentric (d_A = inf): factor 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ..grid import LensGrid
from ._checks import _check_pair, _check_samples, _check_shape, _require_f_number

_STOP_TOLERANCE = 1.0 + 1e-12  # the same tolerance as geometry.views_inside_aperture


def micro_image_scale(camera: Camera) -> float:
    """(d_A + f_s)/d_A: the micro image centre lattice over the lens lattice (1.0 when telecentric).

    ``camera.micro_image_scale``, the number ``lfproc.geometry.micro_image_scale`` gives too.
    """
    return camera.micro_image_scale


def default_grid(camera: Camera, sensor_shape, rotation_deg: float = 0.0, offset_px=(0.0, 0.0)) -> LensGrid:
    """The simulated lattice of micro image centres in sensor pixels (what a white image shows).

    The lens lattice has pitch ``camera.pitch_px`` and kind ``camera.grid``, rotated by
    ``rotation_deg``, with one lens at the sensor centre ((W − 1)/2, (H − 1)/2) + ``offset_px``. The
    micro image centres are that lattice scaled about the sensor centre (the optical axis) by
    :func:`micro_image_scale` (the lens lattice itself when telecentric). The returned grid holds the
    largest rows × cols block of micro images whose centres all lie at least half a pitch inside the
    sensor (complete micro images); :func:`lens_grid_of` gives their lenses. The renderer uses the
    same lattice extended without bound, so the partial cells at the sensor border receive light too.
    """
    height, width = _check_shape(sensor_shape)
    if not (math.isfinite(rotation_deg) and all(math.isfinite(float(v)) for v in offset_px)):
        raise LfprocError(f"rotation_deg and offset_px must be finite, got {rotation_deg}, {offset_px}")
    scale = micro_image_scale(camera)
    pitch = camera.pitch_px * scale
    anchor = ((width - 1) / 2.0 + scale * float(offset_px[0]), (height - 1) / 2.0 + scale * float(offset_px[1]))
    base = LensGrid(camera.grid, pitch, float(rotation_deg), anchor, 1, 1)
    reach = int(math.ceil(math.hypot(height, width) / base.row_spacing_px)) + 2
    idx = np.arange(-reach, reach + 1)
    rr, qq = np.meshgrid(idx, idx, indexing="ij")
    xy = base.lens_xy(rr, qq)
    margin = pitch / 2.0
    inside = ((xy[..., 0] >= -0.5 + margin) & (xy[..., 0] <= width - 0.5 - margin)
              & (xy[..., 1] >= -0.5 + margin) & (xy[..., 1] <= height - 0.5 - margin))
    best = _largest_index_block(inside, even_start=camera.grid == "hexagonal", offset=reach)
    if best is None:
        raise LfprocError(f"sensor {height}x{width} px holds no complete micro lens of pitch {pitch:.3f} px; "
                          f"use a larger sensor_shape")
    r0, q0, rows, cols = best
    origin = tuple(float(v) for v in base.lens_xy(r0, q0))
    return LensGrid(camera.grid, pitch, float(rotation_deg), origin, rows, cols)


def with_exit_pupil(camera: Camera, exit_pupil_distance_mm) -> Camera:
    """``camera`` with the exit pupil a render uses: its own for ``None``, else the given distance (mm, or inf)."""
    if exit_pupil_distance_mm is None:
        return camera
    d_a = exit_pupil_distance_mm
    if isinstance(d_a, bool) or not isinstance(d_a, (int, float)) or math.isnan(d_a) or d_a <= 0:
        raise LfprocError(f"exit_pupil_distance_mm must be a positive distance in mm, inf (telecentric) or None "
                          f"(the camera's), got {d_a!r}")
    if float(d_a) == camera.main_optics.exit_pupil_distance_mm:
        return camera
    return camera.with_optics(replace(camera.main_optics, exit_pupil_distance_mm=float(d_a)))


def lens_grid_of(grid: LensGrid, camera: Camera, sensor_shape) -> LensGrid:
    """The lenses of the micro images in ``grid`` (from :func:`default_grid`): the grid scaled back about the axis.

    Returns ``grid`` itself when telecentric.
    """
    scale = micro_image_scale(camera)
    if scale == 1.0:
        return grid
    height, width = _check_shape(sensor_shape)
    axis = np.array([(width - 1) / 2.0, (height - 1) / 2.0])
    origin = tuple(float(v) for v in axis + (np.asarray(grid.origin_xy_px) - axis) / scale)
    return LensGrid(grid.kind, camera.pitch_px, grid.rotation_deg, origin, grid.rows, grid.cols)


def auto_rim_radius_mm(camera: Camera, sensor_shape) -> float:
    """The default main lens rim: just large enough that the sensor's inscribed circle is unvignetted.

    A sensor point x at most ρ = min(H, W)·p_p/2 from the axis sends rays to U = x + m·(f_s + b_U) + τ,
    where τ lies in the lens cell (|τ| ≤ its circumradius r_cell) and |m| ≤ min(1/(2N), r_cell/f_s)
    (the stop, and the baffle keeping x inside the cell), so the rim radius
    ρ + r_cell + (f_s + b_U)·min(1/(2N), r_cell/f_s) clears all of them. Points beyond the inscribed
    circle (the sensor's corners) are partly vignetted.

    With a finite exit pupil d_A (scale k = (d_A + f_s)/d_A), the slope is m = (−x/d_A + δ)/k with
    |δ| ≤ min(1/(2N) + r_cell/d_A, k·r_cell/f_s) (the pupil, seen from any point of the lens cell,
    and the baffle around the micro image centre), so U = x·(d_A − b_U)/(d_A + f_s) + τ + (f_s + b_U)·δ/k
    and the rim ρ·|d_A − b_U|/(d_A + f_s) + r_cell + (f_s + b_U)·max|δ|/k clears them.
    """
    height, width = _check_shape(sensor_shape)
    _require_f_number(camera)
    rho = 0.5 * min(height, width) * camera.pixel_pitch_mm
    r_cell = camera.mla_pitch_mm * (1.0 / math.sqrt(2.0) if camera.grid == "rectangular" else 1.0 / math.sqrt(3.0))
    lens = camera.main_optics
    f_s, b_u, d_a = camera.mla_focal_length_mm, lens.image_distance_mm, lens.exit_pupil_distance_mm
    if math.isinf(d_a):
        max_slope = min(1.0 / (2.0 * camera.main_optics.f_number), r_cell / f_s)
        return rho + r_cell + (f_s + b_u) * max_slope
    scale = micro_image_scale(camera)
    max_delta = min(1.0 / (2.0 * camera.main_optics.f_number) + r_cell / d_a, scale * r_cell / f_s)
    return rho * abs(d_a - b_u) / (d_a + f_s) + r_cell + (f_s + b_u) * max_delta / scale


@dataclass(frozen=True, eq=False)
class _Setup:
    """Everything about the optics and sampling that does not depend on the scene."""

    camera: Camera             # with the exit pupil of this render
    shape: tuple
    grid: LensGrid             # micro image centres
    lens_grid: LensGrid        # their lenses (grid itself when telecentric)
    axis_px: tuple
    rim_radius_mm: float
    lattice: np.ndarray        # micro image lattice [ox, oy, ux, uy, vx, vy, pitch, row_spacing, is_hex] (px)
    pixel_offsets: np.ndarray  # (n, 2) px, stratified over a pixel
    aperture_offsets: np.ndarray  # (k, 2) mm, stratified over the lens cell, sensor frame
    max_slope2: float

    @property
    def inverse_scale(self) -> float:
        """1 / micro_image_scale: from a micro image centre's height to its lens's (1.0 when telecentric)."""
        return 1.0 / micro_image_scale(self.camera)

    @classmethod
    def build(cls, camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples, aperture_samples,
              exit_pupil_distance_mm=None):
        if not isinstance(camera, Camera):
            raise LfprocError(f"camera must be an lfproc.Camera, got {type(camera).__name__}")
        camera = with_exit_pupil(camera, exit_pupil_distance_mm)
        _require_f_number(camera)
        shape = _check_shape(sensor_shape)
        offset_px = _check_pair(offset_px, "offset_px")
        if isinstance(rotation_deg, bool) or not isinstance(rotation_deg, (int, float)) \
                or not math.isfinite(rotation_deg):
            raise LfprocError(f"rotation_deg must be a finite number of degrees, got {rotation_deg!r}")
        n_pix = _check_samples(pixel_samples, "pixel_samples")
        n_ap = _check_samples(aperture_samples, "aperture_samples")
        if camera.raw_levels(65535.0)[1] > 65535:
            raise LfprocError(f"camera white_level {camera.white_level} exceeds the 16-bit range of simulated raws; "
                              f"use white_level <= 65535")
        grid = default_grid(camera, shape, float(rotation_deg), offset_px)
        rim = _resolve_rim(rim_radius_mm, camera, shape)
        u, v = grid.axes
        lattice = np.array([*grid.origin_xy_px, u[0], u[1], v[0], v[1], grid.pitch_px, grid.row_spacing_px,
                            1.0 if grid.kind == "hexagonal" else 0.0])
        axis = ((shape[1] - 1) / 2.0, (shape[0] - 1) / 2.0)
        stop = 1.0 / (2.0 * camera.main_optics.f_number)
        return cls(camera, shape, grid, lens_grid_of(grid, camera, shape), axis, rim, lattice,
                   pixel_offsets(n_pix),
                   aperture_offsets_mm(camera.grid, camera.mla_pitch_mm, float(rotation_deg), n_ap),
                   stop * stop * _STOP_TOLERANCE)

    def optics_args(self):
        c = self.camera
        rim2 = self.rim_radius_mm ** 2 if math.isfinite(self.rim_radius_mm) else math.inf
        inv_d_a = 0.0 if c.telecentric else 1.0 / c.main_optics.exit_pupil_distance_mm
        lens = c.main_optics
        return (c.mla_focal_length_mm, lens.image_distance_mm, lens.focal_length_mm, self.max_slope2, rim2, inv_d_a)


def pixel_offsets(n: int) -> np.ndarray:
    """n × n stratified sub-sample offsets (px) over a unit pixel, centred: ((i + ½)/n − ½)."""
    g = (np.arange(n) + 0.5) / n - 0.5
    yy, xx = np.meshgrid(g, g, indexing="ij")
    return np.ascontiguousarray(np.stack([xx.ravel(), yy.ravel()], axis=1))


def aperture_offsets_mm(kind: str, pitch_mm: float, rotation_deg: float, n: int) -> np.ndarray:
    """Stratified points over a micro lens cell, relative to its centre, as (x, y) mm in the sensor frame.

    Rectangular: an n × n grid over the square cell. Hexagonal: the Voronoi hexagon (vertices along ±v,
    circumradius p/√3) split into three rhombi O + s·V_k + t·V_(k+2), each with an n × n grid in (s, t);
    both are area-uniform, so every point carries the same weight.
    """
    g = (np.arange(n) + 0.5) / n
    ss, tt = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    if kind == "rectangular":
        along_u, along_v = (ss - 0.5) * pitch_mm, (tt - 0.5) * pitch_mm
    else:
        radius = pitch_mm / math.sqrt(3.0)
        angles = np.radians(30.0 + 60.0 * np.arange(6))
        verts = radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)  # (u, v) components
        pts = [ss[:, None] * verts[2 * k] + tt[:, None] * verts[(2 * k + 2) % 6] for k in range(3)]
        pts = np.concatenate(pts, axis=0)
        along_u, along_v = pts[:, 0], pts[:, 1]
    t = math.radians(rotation_deg)
    u = np.array([math.cos(t), math.sin(t)])
    v = np.array([-math.sin(t), math.cos(t)])
    xy = along_u[:, None] * u + along_v[:, None] * v
    return np.ascontiguousarray(xy)


def _largest_index_block(inside: np.ndarray, even_start: bool, offset: int):
    """Largest axis-aligned (rows × cols) block of True in ``inside`` (rows r, cols q; indices minus ``offset``).

    ``inside`` is a convex lattice region, so each row's True cells are contiguous. Returns
    ``(r0, q0, rows, cols)`` or None. ``even_start`` keeps r0 even (hexagonal row parity).
    """
    n_rows = inside.shape[0]
    has = inside.any(axis=1)
    lo = np.where(has, inside.argmax(axis=1), n_rows * 4)
    hi = np.where(has, inside.shape[1] - 1 - inside[:, ::-1].argmax(axis=1), -n_rows * 4)
    best, best_area = None, 0
    candidates = np.flatnonzero(has)
    for r0 in candidates:
        if even_start and (r0 - offset) % 2:
            continue
        q_lo, q_hi = -np.inf, np.inf
        for r1 in range(r0, n_rows):
            if not has[r1]:
                break
            q_lo, q_hi = max(q_lo, lo[r1]), min(q_hi, hi[r1])
            if q_hi < q_lo:
                break
            area = (r1 - r0 + 1) * (q_hi - q_lo + 1)
            if area > best_area:
                best_area = area
                best = (int(r0 - offset), int(q_lo - offset), int(r1 - r0 + 1), int(q_hi - q_lo + 1))
    return best


def _resolve_rim(rim_radius_mm, camera, shape) -> float:
    if rim_radius_mm is None:
        return math.inf
    if isinstance(rim_radius_mm, str):
        if rim_radius_mm.lower() == "auto":
            return auto_rim_radius_mm(camera, shape)
        if rim_radius_mm.lower() in ("none", "off", "inf"):
            return math.inf
        raise LfprocError(f"rim_radius_mm must be \"auto\", a positive number or None, got {rim_radius_mm!r}")
    if isinstance(rim_radius_mm, bool) or not isinstance(rim_radius_mm, (int, float)) \
            or math.isnan(rim_radius_mm) or rim_radius_mm <= 0:
        raise LfprocError(f"rim_radius_mm must be \"auto\", a positive number or None, got {rim_radius_mm!r}")
    return float(rim_radius_mm)
