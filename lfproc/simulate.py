"""Forward renderer of Standard Plenoptic Camera raw captures, with exact ground truth.

The optics are the paper's paraxial model (Sections 2–3), with an image-side telecentric main lens.
Coordinates are heights in mm from the optical axis, in the sensor's own (x = column, y = row)
directions; the axis meets the sensor at its centre ((W − 1)/2, (H − 1)/2) px.

Ray model (one ray per sensor point x and micro lens aperture point t)
----------------------------------------------------------------------
1. A sensor point ``x`` under micro lens centre ``s`` (the lens whose lattice cell contains ``x``:
   ideal baffles) receives the collimated beam of slope ``m = (s − x)/f_s`` (Eq. 13); it fills the
   micro lens aperture: every ``t`` in the lens's cell (square or hexagon). Heights carry over
   between the principal planes H2s/H1s and H2U/H1U.
2. At the main lens, ``U = t + m·b_U`` (Eq. 16). All rays of slope ``m`` pass the front focal plane
   at ``F = m·f_U`` (Eq. 17); the object-space slope is ``q = (F − U)/f_U`` (Eq. 18) and the ray is
   ``X(z) = U + q·z`` (Eq. 19), z measured from H1U.
3. The aperture stop, a disk of diameter f_U/N in the front focal plane, passes the ray iff
   ``|F| ≤ f_U/(2N)``, i.e. ``|m| ≤ 1/(2N)``: every micro image is a disk of radius f_s/(2N) centred
   under its lens (clipped to the lens cell). The main lens rim, a circle of radius
   ``rim_radius_mm`` in the principal plane, blocks rays with ``|U|`` above it (vignetting).
4. An object plane at distance D from the sensor lies at ``z = D − L`` with L the sensor-to-H1U path
   (``Camera.sensor_to_main_lens_mm``). A ray takes the radiance of the nearest plane whose region it
   hits, else the background (:mod:`lfproc.scene`).

Each pixel integrates stratified sub-samples over its area (``pixel_samples``² points) and over the
micro lens aperture (``aperture_samples``² points per rectangular cell, 3·``aperture_samples``² per
hexagonal cell) and divides by their number: radiance 1 through an unblocked path gives 1.

The numba kernels compile on first use (``cache=True``) and run in parallel over sensor rows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange

from .camera import Camera
from .errors import LfprocError
from .grid import LensGrid
from .scene import KIND_CHECKER, KIND_IMAGE, KIND_NOISE, KIND_SINUSOID, ImageTexture, Scene

#: Rec. 709 luminance weights: how an RGB scene is seen by a monochrome sensor
LUMA_WEIGHTS = (0.2126, 0.7152, 0.0722)
#: the most photons at full scale that shot noise accepts (numpy's Poisson sampler fails near 1e19;
#: far beyond it the noise is below one DN anyway)
MAX_SHOT_NOISE_PHOTONS = 1e12
_STOP_TOLERANCE = 1.0 + 1e-12  # the same tolerance as geometry.views_inside_aperture


@dataclass(frozen=True, eq=False)
class SimulatedCapture:
    """A rendered capture and its ground truth.

    Attributes
    ----------
    raw : ndarray (H, W) uint16
        Sensor DN: the CFA mosaic (or mono image) of the scene.
    white : ndarray (H, W) uint16
        White image: the same optics under uniform radiance 1.
    grid : LensGrid
        Exact lens centres in sensor pixels (the calibration ground truth).
    camera : Camera
    ideal_views : ndarray (m̂, m̂, rows, cols, C) float32 or None
        Scene radiance of each view sample (see :func:`render_ideal_views`); C = 3 with a CFA, else 1.
    ideal_weight : ndarray (m̂, m̂, rows, cols) float32 or None
        Fraction of each ideal sample's rays that pass the stop and the rim.
    plane_label : ndarray (rows, cols) int
        Index into ``planes`` of the plane the central view's chief ray meets at each lens; −1 = background.
    planes : tuple of Plane
        The scene's planes in index order.
    rim_radius_mm : float
        The main lens rim radius used (``inf`` when vignetting was off).
    options : dict
        The render options used.
    """

    raw: np.ndarray
    white: np.ndarray
    grid: LensGrid
    camera: Camera
    ideal_views: np.ndarray | None
    ideal_weight: np.ndarray | None
    plane_label: np.ndarray
    planes: tuple
    rim_radius_mm: float = math.inf
    options: dict = field(default_factory=dict)


# ============================================================================ public API
def render(camera: Camera, scene: Scene, sensor_shape=(480, 640), *, rotation_deg=0.0, offset_px=(0.0, 0.0),
           rim_radius_mm="auto", pixel_samples=2, aperture_samples=3, shot_noise_photons=None,
           read_noise_dn=0.0, exposure=0.8, seed=0, ideal_views=True) -> SimulatedCapture:
    """Render a raw capture, its white image and the ground truth of a scene.

    Parameters
    ----------
    camera : Camera
        Needs ``f_number`` (the aperture stop). ``camera.cfa`` picks mono or a Bayer mosaic.
    scene : Scene
    sensor_shape : (H, W)
        Sensor size in pixels.
    rotation_deg : float
        Lattice rotation (angle of its u axis from +x towards +y).
    offset_px : (dx, dy)
        Shift of the lattice from its default placement (a lens centred on the optical axis).
    rim_radius_mm : "auto", float or None
        Main lens rim radius in its principal plane; ``"auto"`` is :func:`auto_rim_radius_mm`, ``None``
        or ``inf`` turns vignetting off.
    pixel_samples, aperture_samples : int
        Stratified samples per axis over each pixel and over each micro lens aperture.
    shot_noise_photons : float or None
        Photons collected at full scale (Poisson noise), at most :data:`MAX_SHOT_NOISE_PHOTONS`;
        ``None`` = no shot noise.
    read_noise_dn : float
        Standard deviation of Gaussian read noise, in DN.
    exposure : float
        Fraction of the black-to-white range that radiance 1 reaches.
    seed : int
        Seeds the noise (the optics are deterministic). The white image gets the same noise model
        from its own stream of the seed.
    ideal_views : bool
        Also compute ``ideal_views`` and ``ideal_weight`` (about doubles the time).

    Returns
    -------
    SimulatedCapture
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples)
    _check_noise(shot_noise_photons, read_noise_dn, exposure, seed)
    _check_scene(scene)
    arrays = SceneArrays.build(scene, camera)
    radiance = _render_sensor(setup, arrays, channels=3 if camera.cfa != "none" else 1)
    white_radiance = _render_sensor(setup, SceneArrays.uniform(1.0), channels=1)
    raw_rng, white_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(2))
    raw = radiance_to_dn(mosaic(radiance, camera.cfa), camera, exposure, shot_noise_photons, read_noise_dn, raw_rng)
    white = radiance_to_dn(white_radiance[:, :, 0], camera, exposure, shot_noise_photons, read_noise_dn, white_rng)
    views = weight = None
    if ideal_views:
        views, weight = _render_ideal(setup, arrays, channels=3 if camera.cfa != "none" else 1)
    options = dict(sensor_shape=list(setup.shape), rotation_deg=float(rotation_deg),
                   offset_px=[float(v) for v in offset_px], rim_radius_mm=setup.rim_radius_mm,
                   pixel_samples=int(pixel_samples), aperture_samples=int(aperture_samples),
                   shot_noise_photons=shot_noise_photons, read_noise_dn=float(read_noise_dn),
                   exposure=float(exposure), seed=int(seed), ideal_views=bool(ideal_views))
    return SimulatedCapture(raw=raw, white=white, grid=setup.grid, camera=camera, ideal_views=views,
                            ideal_weight=weight, plane_label=central_plane_labels(setup, arrays),
                            planes=scene.planes, rim_radius_mm=setup.rim_radius_mm, options=options)


def render_white(camera: Camera, sensor_shape, *, rotation_deg=0.0, offset_px=(0.0, 0.0), rim_radius_mm="auto",
                 pixel_samples=2, aperture_samples=3, shot_noise_photons=None, read_noise_dn=0.0, exposure=0.8,
                 seed=0) -> tuple[np.ndarray, LensGrid]:
    """Render only the white image (uniform radiance 1): ``(uint16 (H, W) DN, exact LensGrid)``.

    Same optics and options as :func:`render`; the noise uses the white image's stream of ``seed``,
    so ``render_white(...)[0]`` equals ``render(...).white`` for the same arguments.
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples)
    _check_noise(shot_noise_photons, read_noise_dn, exposure, seed)
    white_radiance = _render_sensor(setup, SceneArrays.uniform(1.0), channels=1)
    white_rng = np.random.default_rng(np.random.SeedSequence(int(seed)).spawn(2)[1])
    white = radiance_to_dn(white_radiance[:, :, 0], camera, exposure, shot_noise_photons, read_noise_dn, white_rng)
    return white, setup.grid


def render_radiance(camera: Camera, scene: Scene | None, sensor_shape, *, rotation_deg=0.0, offset_px=(0.0, 0.0),
                    rim_radius_mm="auto", pixel_samples=2, aperture_samples=3, channels=None) -> np.ndarray:
    """The noiseless sensor irradiance before mosaicking and quantisation: float32 (H, W, C).

    ``scene=None`` renders the white image's radiance (uniform 1). ``channels`` defaults to 3 for a
    CFA camera and 1 (luminance) otherwise.
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples)
    if scene is not None:
        _check_scene(scene)
    channels = _check_channels(channels, camera)
    arrays = SceneArrays.uniform(1.0) if scene is None else SceneArrays.build(scene, camera)
    return _render_sensor(setup, arrays, channels)


def render_ideal_views(camera: Camera, scene: Scene, sensor_shape, *, rotation_deg=0.0, offset_px=(0.0, 0.0),
                       rim_radius_mm="auto", pixel_samples=2, aperture_samples=3,
                       channels=None) -> tuple[np.ndarray, np.ndarray, LensGrid]:
    """What a perfect decoder should output: ``(views, weight, grid)``.

    View (ky, kx) at lens (r, q) is the radiance the model gives for an *effective* pixel of pitch
    p_eff = p_m / m̂ centred at the lens centre + (kx − c)·p_eff·u + (ky − c)·p_eff·v (u, v the lattice
    axes, c = (m̂ − 1)/2), integrated over that pixel (a square aligned with u, v) and the micro lens
    aperture, and normalised by the rays that pass the stop and the rim, so it is pure scene radiance.
    ``weight`` is the fraction that passed. Where none passed (views outside the stop) the view holds
    the unblocked average instead, so it is never NaN. Hexagonal grids give views at the hexagonal
    lens centres (the LensGrid's rows × cols). ``channels`` (1 = luminance, :data:`LUMA_WEIGHTS`, or 3)
    defaults to 3 for a CFA camera and 1 otherwise; anything else raises LfprocError.
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples)
    _check_scene(scene)
    channels = _check_channels(channels, camera)
    views, weight = _render_ideal(setup, SceneArrays.build(scene, camera), channels)
    return views, weight, setup.grid


def default_grid(camera: Camera, sensor_shape, rotation_deg: float = 0.0, offset_px=(0.0, 0.0)) -> LensGrid:
    """The simulated micro lens lattice in sensor pixels.

    One lens is centred at the sensor centre ((W − 1)/2, (H − 1)/2) + ``offset_px``; the lattice has
    pitch ``camera.pitch_px`` and kind ``camera.grid``, rotated by ``rotation_deg``. The returned grid
    holds the largest rows × cols block of lenses whose centres all lie at least half a pitch inside
    the sensor (complete micro images). The renderer uses the same lattice extended without bound,
    so the partial cells at the sensor border receive light too.
    """
    height, width = _check_shape(sensor_shape)
    if not (math.isfinite(rotation_deg) and all(math.isfinite(float(v)) for v in offset_px)):
        raise LfprocError(f"rotation_deg and offset_px must be finite, got {rotation_deg}, {offset_px}")
    pitch = camera.pitch_px
    anchor = ((width - 1) / 2.0 + float(offset_px[0]), (height - 1) / 2.0 + float(offset_px[1]))
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


def auto_rim_radius_mm(camera: Camera, sensor_shape) -> float:
    """The default main lens rim: just large enough that the sensor's inscribed circle is unvignetted.

    A sensor point x at most ρ = min(H, W)·p_p/2 from the axis sends rays to U = x + m·(f_s + b_U) + τ,
    where τ lies in the lens cell (|τ| ≤ its circumradius r_cell) and |m| ≤ min(1/(2N), r_cell/f_s)
    (the stop, and the baffle keeping x inside the cell), so the rim radius
    ρ + r_cell + (f_s + b_U)·min(1/(2N), r_cell/f_s) clears all of them. Points beyond the inscribed
    circle (the sensor's corners) are partly vignetted.
    """
    height, width = _check_shape(sensor_shape)
    _require_f_number(camera)
    rho = 0.5 * min(height, width) * camera.pixel_pitch_mm
    r_cell = camera.mla_pitch_mm * (1.0 / math.sqrt(2.0) if camera.grid == "rectangular" else 1.0 / math.sqrt(3.0))
    max_slope = min(1.0 / (2.0 * camera.f_number), r_cell / camera.mla_focal_length_mm)
    return rho + r_cell + (camera.mla_focal_length_mm + camera.image_distance_mm) * max_slope


def mosaic(image: np.ndarray, cfa: str) -> np.ndarray:
    """A single-channel raw (H, W) from an (H, W, C) image: each pixel keeps the colour its CFA filter passes.

    ``cfa="none"`` takes channel 0 of a mono image (or the luminance of an RGB one). A pattern like
    ``"RGGB"`` lists the colours of pixels (0, 0), (0, 1), (1, 0), (1, 1) of each 2×2 tile.
    """
    image = np.asarray(image)
    if cfa == "none":
        if image.shape[2] == 1:
            return image[:, :, 0]
        return np.tensordot(image, np.asarray(LUMA_WEIGHTS, dtype=image.dtype), axes=([2], [0]))
    if image.shape[2] != 3 or len(cfa) != 4 or set(cfa) - set("RGB"):
        raise LfprocError(f"CFA {cfa!r} needs an RGB image and a pattern like RGGB")
    out = np.empty(image.shape[:2], dtype=image.dtype)
    for k, colour in enumerate(cfa):
        dy, dx = divmod(k, 2)
        out[dy::2, dx::2] = image[dy::2, dx::2, "RGB".index(colour)]
    return out


def radiance_to_dn(values: np.ndarray, camera: Camera, exposure: float = 0.8, shot_noise_photons=None,
                   read_noise_dn: float = 0.0, rng: np.random.Generator | None = None) -> np.ndarray:
    """16-bit raw DN = clip(round(black + (white − black)·signal)), signal = exposure·value.

    With ``shot_noise_photons`` P, the signal is Poisson(P·signal)/P (P photons at full scale); read
    noise adds Gaussian DN. The result is clipped to [0, white_level].
    """
    signal = float(exposure) * np.asarray(values, dtype=np.float64)
    if rng is None:
        rng = np.random.default_rng(0)
    if shot_noise_photons is not None:
        photons = float(shot_noise_photons)
        if not (0.0 < photons <= MAX_SHOT_NOISE_PHOTONS):
            raise LfprocError(f"shot_noise_photons must be a positive number up to {MAX_SHOT_NOISE_PHOTONS:g} "
                              f"(or None for no shot noise), got {shot_noise_photons!r}")
        # clipped so that bright (signal >> 1) pixels stay within the Poisson sampler's range
        lam = np.clip(signal * photons, 0.0, 1e18)
        signal = rng.poisson(lam) / photons
    black, white = camera.raw_levels(65535.0)
    dn = black + (white - black) * signal
    if read_noise_dn:
        dn = dn + rng.normal(0.0, float(read_noise_dn), size=dn.shape)
    return np.clip(np.rint(dn), 0.0, white).astype(np.uint16)


def central_plane_labels(setup: "_Setup", arrays: "SceneArrays") -> np.ndarray:
    """Index of the plane the central view's chief ray (through each lens centre, m = 0) meets; −1 = background."""
    centers = setup.grid.centers_xy_px()
    if arrays.order.size == 0:
        return np.full(centers.shape[:2], -1, dtype=np.int64)
    s_mm = (centers - np.array(setup.axis_px)) * setup.camera.pixel_pitch_mm
    labels = _plane_labels_kernel(np.ascontiguousarray(s_mm), setup.camera.main_focal_length_mm,
                                 *arrays.kernel_args())
    return np.where(labels >= 0, arrays.order[np.maximum(labels, 0)], -1).astype(np.int64)


# ============================================================================ setup (pure numpy)
@dataclass(frozen=True, eq=False)
class _Setup:
    """Everything about the optics and sampling that does not depend on the scene."""

    camera: Camera
    shape: tuple
    grid: LensGrid
    axis_px: tuple
    rim_radius_mm: float
    lattice: np.ndarray        # [ox, oy, ux, uy, vx, vy, pitch, row_spacing, is_hex] (px)
    pixel_offsets: np.ndarray  # (n, 2) px, stratified over a pixel
    aperture_offsets: np.ndarray  # (k, 2) mm, stratified over the lens cell, sensor frame
    max_slope2: float

    @classmethod
    def build(cls, camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples, aperture_samples):
        if not isinstance(camera, Camera):
            raise LfprocError(f"camera must be an lfproc.Camera, got {type(camera).__name__}")
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
        stop = 1.0 / (2.0 * camera.f_number)
        return cls(camera, shape, grid, axis, rim, lattice, pixel_offsets(n_pix),
                   aperture_offsets_mm(camera.grid, camera.mla_pitch_mm, float(rotation_deg), n_ap),
                   stop * stop * _STOP_TOLERANCE)

    def optics_args(self):
        c = self.camera
        rim2 = self.rim_radius_mm ** 2 if math.isfinite(self.rim_radius_mm) else math.inf
        return (c.mla_focal_length_mm, c.image_distance_mm, c.main_focal_length_mm, self.max_slope2, rim2)


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


def _require_f_number(camera: Camera) -> None:
    if camera.f_number is None:
        raise LfprocError(f"{camera.source or 'camera'}: rendering needs the aperture stop; add "
                          f"main_lens.f_number to the camera")


def _check_shape(sensor_shape) -> tuple[int, int]:
    try:
        height, width = sensor_shape
    except (TypeError, ValueError):
        raise LfprocError(f"sensor_shape must be (height, width) in pixels, got {sensor_shape!r}") from None
    for value in (height, width):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 2:
            raise LfprocError(f"sensor_shape must be two integers >= 2 (height, width), got {sensor_shape!r}")
    return int(height), int(width)


def _check_pair(value, what: str) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise LfprocError(f"{what} must be two numbers (dx, dy), got {value!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise LfprocError(f"{what} must be finite, got {value!r}")
    return a, b


def _check_samples(value, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= 64:
        raise LfprocError(f"{what} must be an integer from 1 to 64, got {value!r}")
    return int(value)


def _check_scene(scene) -> None:
    if not isinstance(scene, Scene):
        raise LfprocError(f"scene must be an lfproc.scene.Scene, got {type(scene).__name__}; build one with "
                          f"lfproc.scene.Scene(planes, background) or load_scene_file")


def _check_channels(channels, camera: Camera) -> int:
    """The channel count to render: 3 for a CFA camera and 1 otherwise by default; only 1 or 3 exist."""
    if channels is None:
        return 3 if camera.cfa != "none" else 1
    if isinstance(channels, bool) or not isinstance(channels, (int, np.integer)) or channels not in (1, 3):
        raise LfprocError(f"channels must be 1 (luminance) or 3 (RGB), got {channels!r}")
    return int(channels)


def _check_noise(shot_noise_photons, read_noise_dn, exposure, seed) -> None:
    def bad(v):
        return isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
    if shot_noise_photons is not None and (bad(shot_noise_photons) or not
                                           0 < shot_noise_photons <= MAX_SHOT_NOISE_PHOTONS):
        raise LfprocError(f"shot_noise_photons must be a positive number up to {MAX_SHOT_NOISE_PHOTONS:g} or None, "
                          f"got {shot_noise_photons!r}")
    if bad(read_noise_dn) or read_noise_dn < 0:
        raise LfprocError(f"read_noise_dn must be a number >= 0, got {read_noise_dn!r}")
    if bad(exposure) or exposure <= 0:
        raise LfprocError(f"exposure must be a positive number, got {exposure!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise LfprocError(f"seed must be an integer >= 0, got {seed!r}")


# ============================================================================ scene as flat arrays
@dataclass(frozen=True, eq=False)
class SceneArrays:
    """The scene flattened for the kernels, planes sorted nearest first (``order`` maps back to scene indices).

    ``params`` per plane: [low, high, p2, p3, p4, p5, p6] with
    checkerboard p2 = half period; sinusoid p2 = 2π/period, p3 = cos θ, p4 = sin θ, p5 = phase;
    noise p2 = 1/feature, p3 = seed; image p2 = width, p3 = height, p4 = offset into ``images``,
    p5 = rows, p6 = cols.
    """

    z_mm: np.ndarray        # (P,) distance from H1U
    region: np.ndarray      # (P, 4) x0, x1, y0, y1 (±inf when unbounded)
    kind: np.ndarray        # (P,) int64
    params: np.ndarray      # (P, 7)
    center: np.ndarray      # (P, 2)
    tint: np.ndarray        # (P, 3)
    images: np.ndarray      # flat float32 RGB of all image textures
    background: np.ndarray  # (3,)
    order: np.ndarray       # (P,) scene index of each sorted plane

    @classmethod
    def uniform(cls, value: float) -> "SceneArrays":
        """No planes, radiance ``value`` everywhere (the white image)."""
        return cls(np.zeros(0), np.zeros((0, 4)), np.zeros(0, np.int64), np.zeros((0, 7)), np.zeros((0, 2)),
                   np.zeros((0, 3)), np.zeros(1, np.float32), np.full(3, float(value)), np.zeros(0, np.int64))

    @classmethod
    def build(cls, scene: Scene, camera: Camera) -> "SceneArrays":
        inside = camera.sensor_to_main_lens_mm
        order = np.argsort([p.distance_mm for p in scene.planes], kind="stable").astype(np.int64)
        n = len(order)
        z = np.zeros(n)
        region = np.tile(np.array([-np.inf, np.inf, -np.inf, np.inf]), (n, 1))
        kind = np.zeros(n, np.int64)
        params = np.zeros((n, 7))
        center = np.zeros((n, 2))
        tint = np.ones((n, 3))
        images, image_size = [], 0
        for row, index in enumerate(order):
            plane = scene.planes[index]
            if plane.distance_mm <= inside:
                raise LfprocError(f"plane {plane.name or index} at {plane.distance_mm} mm is not in front of the main "
                                  f"lens ({inside:.3f} mm from the sensor); move it farther away")
            z[row] = plane.distance_mm - inside
            tex = plane.texture
            kind[row] = tex.kind
            params[row, :2] = tex.levels()
            center[row] = plane.center_mm
            tint[row] = plane.tint
            if plane.region_mm is not None:
                region[row] = plane.region_mm
            if tex.kind == KIND_CHECKER:
                params[row, 2] = tex.period_mm / 2.0
            elif tex.kind == KIND_SINUSOID:
                angle = math.radians(tex.angle_deg)
                params[row, 2:6] = (2.0 * math.pi / tex.period_mm, math.cos(angle), math.sin(angle),
                                    math.radians(tex.phase_deg))
            elif tex.kind == KIND_NOISE:
                params[row, 2:4] = (1.0 / tex.feature_mm, tex.seed)
            elif isinstance(tex, ImageTexture):
                h, w = tex.pixels.shape[:2]
                params[row, 2:7] = (tex.width_mm, tex.height_mm, image_size, h, w)
                images.append(tex.pixels.ravel())
                image_size += tex.pixels.size
                cx, cy = plane.center_mm
                extent = (cx - tex.width_mm / 2, cx + tex.width_mm / 2, cy - tex.height_mm / 2, cy + tex.height_mm / 2)
                region[row] = (max(region[row, 0], extent[0]), min(region[row, 1], extent[1]),
                               max(region[row, 2], extent[2]), min(region[row, 3], extent[3]))
        flat = np.concatenate(images).astype(np.float32) if images else np.zeros(1, np.float32)
        return cls(z, region, kind, params, center, tint, flat, np.asarray(scene.background, dtype=np.float64), order)

    def kernel_args(self):
        return (self.z_mm, self.region, self.kind, self.params, self.center, self.tint, self.images, self.background)


# ============================================================================ drivers
def _render_sensor(setup: _Setup, arrays: SceneArrays, channels: int) -> np.ndarray:
    height, width = setup.shape
    out = np.empty((height, width, channels), dtype=np.float32)
    _sensor_kernel(out, setup.axis_px[0], setup.axis_px[1], setup.camera.pixel_pitch_mm, setup.lattice,
                   *setup.optics_args(), setup.pixel_offsets, setup.aperture_offsets, *arrays.kernel_args())
    return out


def _render_ideal(setup: _Setup, arrays: SceneArrays, channels: int) -> tuple[np.ndarray, np.ndarray]:
    camera, grid = setup.camera, setup.grid
    m = camera.m_hat
    c = camera.center_index
    p_eff_px = camera.effective_pixel_pitch_mm / camera.pixel_pitch_mm
    u, v = grid.axes
    k = np.arange(m) - c
    view_offsets = (k[None, :, None] * u + k[:, None, None] * v) * p_eff_px  # (ky, kx, 2) px
    sub = setup.pixel_offsets  # the same strata, over an effective pixel aligned with u, v
    sub_px = (sub[:, :1] * u + sub[:, 1:] * v) * p_eff_px  # effective-pixel sub-samples along u, v
    centers = np.ascontiguousarray(grid.centers_xy_px())
    views = np.empty((m, m, grid.rows, grid.cols, channels), dtype=np.float32)
    weight = np.empty((m, m, grid.rows, grid.cols), dtype=np.float32)
    _ideal_kernel(views, weight, centers, np.ascontiguousarray(view_offsets), np.ascontiguousarray(sub_px),
                  setup.axis_px[0], setup.axis_px[1], camera.pixel_pitch_mm, *setup.optics_args(),
                  setup.aperture_offsets, *arrays.kernel_args())
    return views, weight


# ============================================================================ numba kernels
# Compiled on first call and cached on disk (cache=True); every kernel works in float64.
# The luminance weights as module-level floats: numba freezes globals into the compiled code.
_LUMA_R, _LUMA_G, _LUMA_B = LUMA_WEIGHTS

@njit(cache=True, inline="always")
def _nearest_lens_px(px, py, lattice):
    """Centre (x, y) px of the lens whose lattice (Voronoi) cell contains sensor point (px, py)."""
    dx = px - lattice[0]
    dy = py - lattice[1]
    along_u = dx * lattice[2] + dy * lattice[3]
    along_v = dx * lattice[4] + dy * lattice[5]
    pitch = lattice[6]
    if lattice[8] == 0.0:
        cu = np.floor(along_u / pitch + 0.5) * pitch
        cv = np.floor(along_v / pitch + 0.5) * pitch
    else:
        # the nearest hexagonal lattice point lies in one of the two rows around the point
        spacing = lattice[7]
        r0 = np.floor(along_v / spacing)
        best = np.inf
        cu = 0.0
        cv = 0.0
        for step in range(2):
            row = r0 + step
            shift = 0.5 * (int(row) & 1)
            col = np.floor(along_u / pitch - shift + 0.5)
            cand_u = (col + shift) * pitch
            cand_v = row * spacing
            d2 = (along_u - cand_u) ** 2 + (along_v - cand_v) ** 2
            if d2 < best:
                best = d2
                cu = cand_u
                cv = cand_v
    return lattice[0] + cu * lattice[2] + cv * lattice[4], lattice[1] + cu * lattice[3] + cv * lattice[5]


@njit(cache=True, inline="always")
def _hash01(ix, iy, seed):
    """A deterministic pseudo-random number in [0, 1] for integer lattice point (ix, iy)."""
    h = (ix * 374761393 + iy * 668265263 + seed * 1442695041 + 1013904223) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    h = ((h ^ (h >> 16)) * 2246822519) & 0xFFFFFFFF
    h = h ^ (h >> 15)
    return h / 4294967295.0


@njit(cache=True, inline="always")
def _value_noise(x, y, seed):
    """Value noise: lattice values blended with the quintic fade 6t⁵ − 15t⁴ + 10t³ (C² smooth)."""
    fx = np.floor(x)
    fy = np.floor(y)
    ix = np.int64(fx)
    iy = np.int64(fy)
    tx = x - fx
    ty = y - fy
    sx = tx * tx * tx * (tx * (tx * 6.0 - 15.0) + 10.0)
    sy = ty * ty * ty * (ty * (ty * 6.0 - 15.0) + 10.0)
    v00 = _hash01(ix, iy, seed)
    v10 = _hash01(ix + 1, iy, seed)
    v01 = _hash01(ix, iy + 1, seed)
    v11 = _hash01(ix + 1, iy + 1, seed)
    top = v00 + (v10 - v00) * sx
    bottom = v01 + (v11 - v01) * sx
    return top + (bottom - top) * sy


@njit(cache=True, inline="always")
def _texture_value(kind, par, x, y):
    """Scalar texture value t in [0, 1] at plane point (x, y) relative to the texture origin."""
    if kind == KIND_CHECKER:
        i = np.int64(np.floor(x / par[2]))
        j = np.int64(np.floor(y / par[2]))
        return float((i + j) & 1)
    if kind == KIND_SINUSOID:
        return 0.5 + 0.5 * np.cos(par[2] * (x * par[3] + y * par[4]) + par[5])
    if kind == KIND_NOISE:
        seed = np.int64(par[3])
        fine = _value_noise(2.0 * x * par[2] + 17.25, 2.0 * y * par[2] + 31.5, seed + 7919)
        return (_value_noise(x * par[2], y * par[2], seed) + 0.5 * fine) / 1.5
    return 1.0  # uniform


@njit(cache=True, inline="always")
def _image_sample(par, images, x, y, channel):
    """Bilinear sample of an image texture (row 0 at the smallest y), edge pixels clamped."""
    rows = np.int64(par[5])
    cols = np.int64(par[6])
    col = (x / par[2] + 0.5) * cols - 0.5
    row = (y / par[3] + 0.5) * rows - 0.5
    col = min(max(col, 0.0), cols - 1.0)
    row = min(max(row, 0.0), rows - 1.0)
    c0 = min(np.int64(col), cols - 2) if cols > 1 else 0
    r0 = min(np.int64(row), rows - 2) if rows > 1 else 0
    c1 = min(c0 + 1, cols - 1)
    r1 = min(r0 + 1, rows - 1)
    wc = col - c0
    wr = row - r0
    base = np.int64(par[4])
    v00 = images[base + (r0 * cols + c0) * 3 + channel]
    v01 = images[base + (r0 * cols + c1) * 3 + channel]
    v10 = images[base + (r1 * cols + c0) * 3 + channel]
    v11 = images[base + (r1 * cols + c1) * 3 + channel]
    return (v00 * (1 - wc) + v01 * wc) * (1 - wr) + (v10 * (1 - wc) + v11 * wc) * wr


@njit(cache=True, inline="always")
def _scene_radiance(ux, uy, qx, qy, z, region, kind, par, center, tint, images, background):
    """RGB radiance along the object-space ray X(z) = U + q·z, and the (sorted) index of the plane hit (−1: none).

    Plane coordinates are the ray heights negated (the picture as seen in the capture, upright).
    """
    for p in range(z.shape[0]):
        x = -(ux + qx * z[p])
        y = -(uy + qy * z[p])
        if x < region[p, 0] or x >= region[p, 1] or y < region[p, 2] or y >= region[p, 3]:
            continue
        tx = x - center[p, 0]
        ty = y - center[p, 1]
        low = par[p, 0]
        span = par[p, 1] - par[p, 0]
        if kind[p] == KIND_IMAGE:
            return ((low + span * _image_sample(par[p], images, tx, ty, 0)) * tint[p, 0],
                    (low + span * _image_sample(par[p], images, tx, ty, 1)) * tint[p, 1],
                    (low + span * _image_sample(par[p], images, tx, ty, 2)) * tint[p, 2], p)
        value = low + span * _texture_value(kind[p], par[p], tx, ty)
        return value * tint[p, 0], value * tint[p, 1], value * tint[p, 2], p
    return background[0], background[1], background[2], -1


@njit(cache=True, inline="always")
def _store(out, y, x, r, g, b, scale):
    if out.shape[2] == 1:
        out[y, x, 0] = (_LUMA_R * r + _LUMA_G * g + _LUMA_B * b) * scale
    else:
        out[y, x, 0] = r * scale
        out[y, x, 1] = g * scale
        out[y, x, 2] = b * scale


@njit(cache=True, parallel=True)
def _sensor_kernel(out, axis_x, axis_y, pixel_mm, lattice, f_s, b_u, f_u, max_slope2, rim2,
                   pix_off, ap_off, z, region, kind, par, center, tint, images, background):
    """Sensor irradiance: each pixel averages pix_off × ap_off rays (zero for the blocked ones)."""
    height, width = out.shape[0], out.shape[1]
    n_pix = pix_off.shape[0]
    n_ap = ap_off.shape[0]
    scale = 1.0 / (n_pix * n_ap)
    for y in prange(height):
        for x in range(width):
            r = 0.0
            g = 0.0
            b = 0.0
            for i in range(n_pix):
                px = x + pix_off[i, 0]
                py = y + pix_off[i, 1]
                sx, sy = _nearest_lens_px(px, py, lattice)
                s_x = (sx - axis_x) * pixel_mm
                s_y = (sy - axis_y) * pixel_mm
                mx = (s_x - (px - axis_x) * pixel_mm) / f_s
                my = (s_y - (py - axis_y) * pixel_mm) / f_s
                if mx * mx + my * my > max_slope2:
                    continue  # outside the aperture stop, whatever the aperture point
                for j in range(n_ap):
                    u_x = s_x + ap_off[j, 0] + mx * b_u
                    u_y = s_y + ap_off[j, 1] + my * b_u
                    if u_x * u_x + u_y * u_y > rim2:
                        continue
                    rr, gg, bb, _ = _scene_radiance(u_x, u_y, mx - u_x / f_u, my - u_y / f_u, z, region, kind,
                                                    par, center, tint, images, background)
                    r += rr
                    g += gg
                    b += bb
            _store(out, y, x, r, g, b, scale)


@njit(cache=True, parallel=True)
def _ideal_kernel(views, weight, centers, view_off, sub_off, axis_x, axis_y, pixel_mm, f_s, b_u, f_u,
                  max_slope2, rim2, ap_off, z, region, kind, par, center, tint, images, background):
    """Ideal views: per lens and view, the mean radiance of the passing rays and the passing fraction."""
    m = views.shape[0]
    rows, cols = views.shape[2], views.shape[3]
    channels = views.shape[4]
    n_sub = sub_off.shape[0]
    n_ap = ap_off.shape[0]
    total = n_sub * n_ap
    for row in prange(rows):
        for col in range(cols):
            s_x = (centers[row, col, 0] - axis_x) * pixel_mm
            s_y = (centers[row, col, 1] - axis_y) * pixel_mm
            for ky in range(m):
                for kx in range(m):
                    r = 0.0
                    g = 0.0
                    b = 0.0
                    passed = 0
                    fallback = False
                    for attempt in range(2):  # the second pass (all rays, unblocked) only when none passed
                        for i in range(n_sub):
                            dx_mm = (view_off[ky, kx, 0] + sub_off[i, 0]) * pixel_mm
                            dy_mm = (view_off[ky, kx, 1] + sub_off[i, 1]) * pixel_mm
                            mx = -dx_mm / f_s
                            my = -dy_mm / f_s
                            if not fallback and mx * mx + my * my > max_slope2:
                                continue
                            for j in range(n_ap):
                                u_x = s_x + ap_off[j, 0] + mx * b_u
                                u_y = s_y + ap_off[j, 1] + my * b_u
                                if not fallback and u_x * u_x + u_y * u_y > rim2:
                                    continue
                                rr, gg, bb, _ = _scene_radiance(u_x, u_y, mx - u_x / f_u, my - u_y / f_u, z, region,
                                                                kind, par, center, tint, images, background)
                                r += rr
                                g += gg
                                b += bb
                                passed += 1
                        if passed > 0:
                            break
                        fallback = True
                    weight[ky, kx, row, col] = 0.0 if fallback else passed / total
                    scale = 1.0 / passed
                    if channels == 1:
                        views[ky, kx, row, col, 0] = (_LUMA_R * r + _LUMA_G * g + _LUMA_B * b) * scale
                    else:
                        views[ky, kx, row, col, 0] = r * scale
                        views[ky, kx, row, col, 1] = g * scale
                        views[ky, kx, row, col, 2] = b * scale


@njit(cache=True)
def _plane_labels_kernel(s_mm, f_u, z, region, kind, par, center, tint, images, background):
    """Sorted plane index hit by the chief ray through each lens centre with slope m = 0 (U = s, q = −s/f_U)."""
    rows, cols = s_mm.shape[0], s_mm.shape[1]
    labels = np.empty((rows, cols), dtype=np.int64)
    for row in range(rows):
        for col in range(cols):
            sx = s_mm[row, col, 0]
            sy = s_mm[row, col, 1]
            _, _, _, hit = _scene_radiance(sx, sy, -sx / f_u, -sy / f_u, z, region, kind, par, center, tint,
                                           images, background)
            labels[row, col] = hit
    return labels
