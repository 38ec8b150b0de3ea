"""Forward renderer of Standard Plenoptic Camera raw captures, with exact ground truth.

The optics are the paper's paraxial model (Sections 2–3), with an image-side telecentric main lens
or, with a finite exit pupil, its extension by Hahne et al. (IJCV 2018). Coordinates are heights in
mm from the optical axis, in the sensor's own (x = column, y = row) directions; the axis meets the
sensor at its centre ((W − 1)/2, (H − 1)/2) px.

Ray model (one ray per sensor point x and micro lens aperture point t)
----------------------------------------------------------------------
1. A sensor point ``x`` under micro lens centre ``s`` (the lens whose micro image cell contains
   ``x``: ideal baffles) receives the collimated beam of slope ``m = (s − x)/f_s`` (Eq. 13); it fills
   the micro lens aperture: every ``t`` in the lens's cell (square or hexagon). Heights carry over
   between the principal planes H2s/H1s and H2U/H1U.
2. At the main lens, ``U = t + m·b_U`` (Eq. 16). All rays of slope ``m`` pass the front focal plane
   at ``F = m·f_U`` (Eq. 17); the object-space slope is ``q = (F − U)/f_U`` (Eq. 18) and the ray is
   ``X(z) = U + q·z`` (Eq. 19), z measured from H1U.
3. Telecentric (``exit_pupil_distance_mm`` = inf): the aperture stop, a disk of diameter f_U/N in
   the front focal plane, passes the ray iff ``|F| ≤ f_U/(2N)``, i.e. ``|m| ≤ 1/(2N)``: every micro
   image is a disk of radius f_s/(2N) centred under its lens (clipped to the lens cell).
   Finite exit pupil d_A: the stop sits where the main lens images it to a disk of diameter d_A/N at
   d_A in front of the MLA (the exit pupil, seen from image space); the image-space ray meets that
   plane at ``t + m·d_A`` and passes iff ``|t + m·d_A| ≤ d_A/(2N)``. Rays through a lens centre s
   then come from around ``m = −s/d_A``: the micro image is the same disk, centred at
   s·(d_A + f_s)/d_A, drifted outwards (the micro image cells, the "baffles" of step 1, are that
   scaled lattice). The object-space rays (step 2) do not change: the main lens images as before.
   The main lens rim, a circle of radius ``rim_radius_mm`` in the principal plane, blocks rays with
   ``|U|`` above it (vignetting).
4. An object plane at distance D from the sensor lies at ``z = D − L`` with L the sensor-to-H1U path
   (``MainLens.sensor_path_mm``). A ray takes the radiance of the nearest plane whose region it
   hits, else the background (:mod:`lfproc.simulate._scene`).

Each pixel integrates stratified sub-samples over its area (``pixel_samples``² points) and over the
micro lens aperture (``aperture_samples``² points per rectangular cell, 3·``aperture_samples``² per
hexagonal cell) and divides by their number: radiance 1 through an unblocked path gives 1.

The numba kernels compile on first use (``cache=True``) and run in parallel over sensor rows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ..grid import LensGrid
from ._checks import _check_channels, _check_noise
from ._ground_truth import central_view_truth
from ._scene import Scene
from ._scene_arrays import SceneArrays
from ._sensor import mosaic, radiance_to_dn
from ._setup import _Setup
from ._trace import Progress, ideal_rays, render_ideal, render_sensor, sensor_rays


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
        Exact micro image centres in sensor pixels: what a white image shows and calibration must
        find (the lens centres when telecentric).
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
    depth_mm : ndarray (rows, cols) float64
        Per lens of ``grid``: the distance from the sensor of the surface point that the central
        view's chief ray meets (a plane's depth there; NaN = background).
    lens_grid : LensGrid
        The physical micro lens centres in sensor pixels (equal to ``grid`` when telecentric).
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
    depth_mm: np.ndarray | None = None
    lens_grid: LensGrid | None = None


def render(camera: Camera, scene: Scene, sensor_shape=(480, 640), *, rotation_deg=0.0, offset_px=(0.0, 0.0),
           rim_radius_mm="auto", pixel_samples=2, aperture_samples=3, shot_noise_photons=None,
           read_noise_dn=0.0, exposure=0.8, seed=0, ideal_views=True,
           exit_pupil_distance_mm=None, progress=None) -> SimulatedCapture:
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
    exit_pupil_distance_mm : float or None
        d_A, the exit pupil's distance in front of the micro lens array (mm); ``inf`` is telecentric,
        ``None`` (the default) takes ``camera.main_optics.exit_pupil_distance_mm``. The capture's ``camera``
        carries the value used.
    progress : callable or None
        Called as ``progress(fraction_done, stage)`` after each band of rows (``stage`` is "capture",
        "white image" or "ideal views"); for progress bars.

    Returns
    -------
    SimulatedCapture
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples, exit_pupil_distance_mm)
    camera = setup.camera
    _check_noise(shot_noise_photons, read_noise_dn, exposure, seed)
    _check_scene(scene)
    arrays = SceneArrays.build(scene, camera)
    bar = Progress(progress, sensor_rays(setup) * 2 + (ideal_rays(setup) if ideal_views else 0.0))
    radiance = render_sensor(setup, arrays, 3 if camera.cfa != "none" else 1, bar, "capture")
    white_radiance = render_sensor(setup, SceneArrays.uniform(1.0), 1, bar, "white image")
    raw_rng, white_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(2))
    raw = radiance_to_dn(mosaic(radiance, camera.cfa), camera, exposure, shot_noise_photons, read_noise_dn, raw_rng)
    white = radiance_to_dn(white_radiance[:, :, 0], camera, exposure, shot_noise_photons, read_noise_dn, white_rng)
    views = weight = None
    if ideal_views:
        views, weight = render_ideal(setup, arrays, 3 if camera.cfa != "none" else 1, bar)
    options = dict(sensor_shape=list(setup.shape), rotation_deg=float(rotation_deg),
                   offset_px=[float(v) for v in offset_px], rim_radius_mm=setup.rim_radius_mm,
                   pixel_samples=int(pixel_samples), aperture_samples=int(aperture_samples),
                   shot_noise_photons=shot_noise_photons, read_noise_dn=float(read_noise_dn),
                   exposure=float(exposure), seed=int(seed), ideal_views=bool(ideal_views),
                   exit_pupil_distance_mm=camera.main_optics.exit_pupil_distance_mm)
    labels, depth_mm = central_view_truth(setup, arrays)
    return SimulatedCapture(raw=raw, white=white, grid=setup.grid, camera=camera, ideal_views=views,
                            ideal_weight=weight, plane_label=labels, planes=scene.planes,
                            rim_radius_mm=setup.rim_radius_mm, options=options, depth_mm=depth_mm,
                            lens_grid=setup.lens_grid)


def render_white(camera: Camera, sensor_shape, *, rotation_deg=0.0, offset_px=(0.0, 0.0), rim_radius_mm="auto",
                 pixel_samples=2, aperture_samples=3, shot_noise_photons=None, read_noise_dn=0.0, exposure=0.8,
                 seed=0, exit_pupil_distance_mm=None) -> tuple[np.ndarray, LensGrid]:
    """Render only the white image (uniform radiance 1): ``(uint16 (H, W) DN, exact micro image centre LensGrid)``.

    Same optics and options as :func:`render`; the noise uses the white image's stream of ``seed``,
    so ``render_white(...)[0]`` equals ``render(...).white`` for the same arguments.
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples, exit_pupil_distance_mm)
    _check_noise(shot_noise_photons, read_noise_dn, exposure, seed)
    white_radiance = render_sensor(setup, SceneArrays.uniform(1.0), channels=1)
    white_rng = np.random.default_rng(np.random.SeedSequence(int(seed)).spawn(2)[1])
    white = radiance_to_dn(white_radiance[:, :, 0], camera, exposure, shot_noise_photons, read_noise_dn, white_rng)
    return white, setup.grid


def render_radiance(camera: Camera, scene: Scene | None, sensor_shape, *, rotation_deg=0.0, offset_px=(0.0, 0.0),
                    rim_radius_mm="auto", pixel_samples=2, aperture_samples=3, channels=None,
                    exit_pupil_distance_mm=None) -> np.ndarray:
    """The noiseless sensor irradiance before mosaicking and quantisation: float32 (H, W, C).

    ``scene=None`` renders the white image's radiance (uniform 1). ``channels`` defaults to 3 for a
    CFA camera and 1 (luminance) otherwise.
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples, exit_pupil_distance_mm)
    if scene is not None:
        _check_scene(scene)
    channels = _check_channels(channels, camera)
    arrays = SceneArrays.uniform(1.0) if scene is None else SceneArrays.build(scene, camera)
    return render_sensor(setup, arrays, channels)


def render_ideal_views(camera: Camera, scene: Scene, sensor_shape, *, rotation_deg=0.0, offset_px=(0.0, 0.0),
                       rim_radius_mm="auto", pixel_samples=2, aperture_samples=3, channels=None,
                       exit_pupil_distance_mm=None) -> tuple[np.ndarray, np.ndarray, LensGrid]:
    """What a perfect decoder should output: ``(views, weight, grid)``.

    View (ky, kx) at lens (r, q) is the radiance the model gives for an *effective* pixel of pitch
    p_eff = p_m·k / m̂ centred at the micro image centre + (kx − c)·p_eff·u + (ky − c)·p_eff·v (u, v
    the lattice axes, c = (m̂ − 1)/2, k = :func:`micro_image_scale`, 1 when telecentric: the micro
    image pitch over m̂, as a decoder samples it), integrated over that pixel (a square aligned with
    u, v) and the micro lens aperture, and normalised by the rays that pass the stop and the rim, so
    it is pure scene radiance. ``weight`` is the fraction that passed. Where none passed (views
    outside the stop) the view holds the unblocked average instead, so it is never NaN. Hexagonal
    grids give views at the hexagonal lens centres (the LensGrid's rows × cols). ``channels``
    (1 = luminance, :data:`LUMA_WEIGHTS`, or 3) defaults to 3 for a CFA camera and 1 otherwise;
    anything else raises LfprocError. ``exit_pupil_distance_mm`` as in :func:`render`.

    Parameters
    ----------
    camera : Camera
    scene : Scene
    sensor_shape : (int, int)
        (H, W) pixels of the sensor the lattice lies on.
    rotation_deg, offset_px : float, (float, float)
        The lattice's rotation and offset on the sensor.
    rim_radius_mm : float or "auto"
        The micro lens aperture's radius.
    pixel_samples, aperture_samples : int
        Samples per pixel axis and per aperture axis.
    channels : {1, 3} or None
    exit_pupil_distance_mm : float or None

    Returns
    -------
    views : ndarray (m̂, m̂, Ny, Nx, C) float32
    weight : ndarray (m̂, m̂, Ny, Nx) float32
        The fraction of each view's rays that passed the stop and the rim.
    grid : LensGrid
    """
    setup = _Setup.build(camera, sensor_shape, rotation_deg, offset_px, rim_radius_mm, pixel_samples,
                         aperture_samples, exit_pupil_distance_mm)
    _check_scene(scene)
    channels = _check_channels(channels, camera)
    views, weight = render_ideal(setup, SceneArrays.build(scene, camera), channels)
    return views, weight, setup.grid


def _check_scene(scene) -> None:
    if not isinstance(scene, Scene):
        raise LfprocError(f"scene must be an lfproc.simulate.Scene, got {type(scene).__name__}; build one with "
                          f"lfproc.simulate.Scene(planes, background) or load_scene_file")
