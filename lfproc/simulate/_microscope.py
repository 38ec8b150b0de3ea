"""Renders of a light-field microscope: fluorescent beads and textured sheets at known depths.

The optics (Levoy et al., "Light Field Microscopy", SIGGRAPH 2006; Broxton et al. 2013) with the
camera's ``[microscope]`` table: an infinity-corrected objective (focal length f_tube/M) and its tube
lens, a micro lens array at the native image plane, the sensor at the lenslets' focal plane (behind a
relay of magnification R). Rays are traced backwards from a sample point at the lenslets' focal plane:

lenslet
    a sample at P in the cell of the lens centred at s (ideal baffles) came through the lens at a
    point t of its aperture with image-side direction tangent u' = (P − s)/f_s (a thin lens focused
    at infinity: every ray of one direction meets its focal plane at s + f_s·u').
tube lens and objective
    a doubly telecentric 4f relay, aplanatic: the ray crossing the native image plane at t left the
    native object plane at x₀ = −t/M (the image is inverted) with object-side direction sines
    (α, β) = −(M/n)·(sine components of u'), the Abbe sine condition n·sin θ = M·sin θ' — exact at
    any NA, not paraxial — and γ = √(1 − α² − β²). Rays with n·sin θ > NA miss the aperture stop.
object space
    the ray X(z) = x₀ + z·(α, β)/γ, z from the native object plane, positive towards the objective
    (the contract's z_um). A bead of radius r emits uniformly: a ray collects its chord through the
    sphere. A sheet at z_s emits its texture over a thin layer: a ray collects texture/γ. Emission
    adds (fluorescence: no occlusion); the background is dark.

:func:`render_microscope_views` gives what an ideal decoder delivers (view (ky, kx) of lens (r, q): the
mean over a sample pitch p_p = p_m/m̂ around offset (k − c)·p_p and over the lens aperture, with the
fraction of rays inside the NA), :func:`render_microscope_sensor` the sensor image (and, with no scene,
the white image: uniform emission). Pure numpy, a few million rays per second.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..camera import Camera, Microscope
from ..errors import LfprocError
from ._setup import aperture_offsets_mm, pixel_offsets

MM_PER_UM = 1e-3
#: rays traced per chunk (bounds the temporaries)
RAY_CHUNK = 1 << 20


@dataclass(frozen=True)
class Bead:
    """A fluorescent sphere at (x_um, y_um, z_um) in the sample (z from the native object plane,
    positive towards the objective), radius ``radius_um``, emission ``brightness`` per µm of path.

    Attributes
    ----------
    x_um, y_um, z_um : float
        Its centre in the object, µm from the optical axis and from the native object plane.
    radius_um : float
    brightness : float
    """

    x_um: float
    y_um: float
    z_um: float
    radius_um: float = 1.0
    brightness: float = 1.0

    def __post_init__(self):
        _finite(self, ("x_um", "y_um", "z_um", "brightness"), positive=("radius_um",))


@dataclass(frozen=True)
class Sheet:
    """A thin fluorescent sheet at depth ``z_um`` with a texture: the sum of ``waves`` cosines
    of period ``period_um`` (random directions and phases from ``seed``), levels in [low, high].

    Attributes
    ----------
    z_um : float
        Its depth, µm from the native object plane.
    period_um : float
        The period of each cosine of the texture, µm.
    waves, seed : int
        Number of random waves of the texture and their seed.
    low, high : float
        Emission range.
    """

    z_um: float
    period_um: float = 10.0
    waves: int = 6
    seed: int = 0
    low: float = 0.2
    high: float = 1.0

    def __post_init__(self):
        _finite(self, ("z_um", "low", "high"), positive=("period_um",))
        if isinstance(self.waves, bool) or not isinstance(self.waves, int) or self.waves < 1:
            raise LfprocError(f"Sheet: waves must be a positive integer, got {self.waves!r}")

    def value(self, x_um: np.ndarray, y_um: np.ndarray) -> np.ndarray:
        rng = np.random.default_rng(self.seed)
        angle = rng.uniform(0.0, math.pi, self.waves)
        phase = rng.uniform(0.0, 2.0 * math.pi, self.waves)
        scale = rng.uniform(0.7, 1.4, self.waves)
        k = 2.0 * math.pi / self.period_um
        total = np.zeros(np.broadcast(x_um, y_um).shape)
        for a, p, s in zip(angle, phase, scale):
            total += np.cos(k * s * (x_um * math.cos(a) + y_um * math.sin(a)) + p)
        return self.low + (self.high - self.low) * (0.5 + 0.5 * total / self.waves)


@dataclass(frozen=True)
class MicroscopeScene:
    """Beads and sheets (emission adds; a dark background).

    Attributes
    ----------
    beads : tuple of Bead
    sheets : tuple of Sheet
    """

    beads: tuple = field(default_factory=tuple)
    sheets: tuple = field(default_factory=tuple)


def _finite(obj, names, positive=()) -> None:
    """One-line LfprocError for a non-finite field of a bead or sheet, or a non-positive size."""
    kind = type(obj).__name__
    for name in (*names, *positive):
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise LfprocError(f"{kind}: {name} must be a finite number, got {value!r}")
        if name in positive and value <= 0:
            raise LfprocError(f"{kind}: {name} must be positive, got {value!r}")


def _scope(camera: Camera) -> Microscope:
    """The objective + tube lens this renderer traces (the camera's main optics), or a one-line refusal."""
    optics = camera.main_optics if isinstance(camera, Camera) else None
    if not isinstance(optics, Microscope):
        raise LfprocError("a microscope render needs a microscope camera (a [microscope] table)")
    return optics


def object_rays(camera: Camera, t_mm: np.ndarray, u_tan: np.ndarray, na_offset=(0.0, 0.0)):
    """Object-space rays of image-side rays at the native image plane: ``(x0_um (…, 2), dir (…, 3), inside)``.

    ``t_mm`` (…, 2): where the ray crosses the micro lens array, mm from the optical axis; ``u_tan``
    (…, 2): its image-side direction tangents. ``x0_um`` is the ray's point on the native object plane,
    ``dir`` its unit direction (α, β, γ) in the medium (sine condition), ``inside`` whether it passes
    the objective's aperture (n·sin θ ≤ NA). ``na_offset`` (x, y), in units of n·sin θ, moves the
    aperture's centre off the axis (an objective pupil off the axis, a tilted illumination cone):
    ``inside`` is then |n·(α, β) − na_offset| ≤ NA, and the white image's discs move by
    −f_s·tan θ' with sin θ' = na_offset/M at the lenslets.
    """
    scope = _scope(camera)
    norm = np.sqrt(1.0 + (u_tan ** 2).sum(axis=-1, keepdims=True))
    sines = -(scope.objective_magnification / scope.immersion_index) * u_tan / norm
    radial2 = (sines ** 2).sum(axis=-1)
    off = np.asarray(na_offset, dtype=np.float64) / scope.immersion_index
    aperture2 = ((sines - off) ** 2).sum(axis=-1)
    inside = aperture2 * scope.immersion_index ** 2 <= scope.numerical_aperture ** 2 * (1.0 + 1e-12)
    gamma = np.sqrt(np.clip(1.0 - radial2, 1e-12, None))
    x0_um = -t_mm / scope.objective_magnification / MM_PER_UM
    return x0_um, np.concatenate([sines, gamma[..., None]], axis=-1), inside


def ray_emission(scene: MicroscopeScene, x0_um: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Light collected along each ray (x0 on the native object plane, unit direction): beads' chords
    times their brightness plus sheets' texture/γ."""
    total = np.zeros(x0_um.shape[:-1])
    slope = direction[..., :2] / direction[..., 2:3]
    for bead in scene.beads:
        # the line X(z) = (x0 + z·slope, z): distance² of the bead centre to it along the unit direction
        w = np.stack([bead.x_um - x0_um[..., 0], bead.y_um - x0_um[..., 1],
                      np.broadcast_to(bead.z_um, x0_um.shape[:-1])], axis=-1)
        along = (w * direction).sum(axis=-1)
        dist2 = (w * w).sum(axis=-1) - along * along
        total += bead.brightness * 2.0 * np.sqrt(np.clip(bead.radius_um ** 2 - dist2, 0.0, None))
    for sheet in scene.sheets:
        x = x0_um + sheet.z_um * slope
        total += sheet.value(x[..., 0], x[..., 1]) / direction[..., 2]
    return total


def _lens_centres_mm(camera: Camera, lens_shape) -> np.ndarray:
    """(Ny, Nx, 2) lens centres (x, y) in mm at the MLA, the optical axis at the middle of the array."""
    ny, nx = lens_shape
    y = (np.arange(ny) - (ny - 1) / 2.0) * camera.mla_pitch_mm
    x = (np.arange(nx) - (nx - 1) / 2.0) * camera.mla_pitch_mm
    return np.stack(np.meshgrid(x, y), axis=-1)


def lens_of_point(camera: Camera, lens_shape, x_um: float, y_um: float) -> tuple[float, float]:
    """(row, col) — fractional — of the lens that images object point (x, y) on the native object plane."""
    scope = _scope(camera)
    ny, nx = lens_shape
    t = -np.array([x_um, y_um]) * MM_PER_UM * scope.objective_magnification
    return float(t[1] / camera.mla_pitch_mm + (ny - 1) / 2.0), float(t[0] / camera.mla_pitch_mm + (nx - 1) / 2.0)


def render_microscope_views(camera: Camera, scene: MicroscopeScene, lens_shape, *, pixel_samples: int = 2,
                            aperture_samples: int = 3, na_offset=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """Ideal decoded views ``(m̂, m̂, Ny, Nx, 1)`` float32 and the fraction of their rays inside the NA (m̂, m̂).

    Views outside the NA (fraction 0) are delivered as 0, as the decoder delivers them; ``na_offset``:
    see :func:`object_rays`.

    Parameters
    ----------
    camera : Camera
        A microscope camera.
    scene : MicroscopeScene
    lens_shape : (int, int)
        (Ny, Nx) lenses.
    pixel_samples, aperture_samples : int
    na_offset : (float, float)

    Returns
    -------
    views : ndarray (m̂, m̂, Ny, Nx, 1) float32
    fraction : ndarray (m̂, m̂) float
    """
    _scope(camera)
    m, c = camera.m_hat, camera.center_index
    pitch = camera.sample_pitch_mm
    sub = pixel_offsets(pixel_samples) * pitch                                    # (S, 2) mm
    ap = aperture_offsets_mm("rectangular", camera.mla_pitch_mm, 0.0, aperture_samples)   # (A, 2) mm
    lenses = _lens_centres_mm(camera, lens_shape).reshape(-1, 2)                  # (L, 2)
    views = np.zeros((m, m, lenses.shape[0]))
    fraction = np.zeros((m, m))
    for ky in range(m):
        for kx in range(m):
            offset = np.array([kx - c, ky - c]) * pitch + sub                     # (S, 2) at the focal plane
            u = np.broadcast_to((offset / camera.mla_focal_length_mm)[:, None, None, :],
                                (len(sub), len(ap), 1, 2))
            t = lenses[None, None, :, :] + ap[None, :, None, :]                   # (1, A, L, 2)
            x0, direction, inside = object_rays(camera, t, u, na_offset)
            rays = (len(sub), len(ap), lenses.shape[0])
            inside = np.broadcast_to(inside, rays)
            passed = inside.sum(axis=(0, 1))
            if not passed.any():
                continue
            light = np.where(inside, ray_emission(scene, np.broadcast_to(x0, rays + (2,)),
                                                  np.broadcast_to(direction, rays + (3,))), 0.0)
            views[ky, kx] = light.sum(axis=(0, 1)) / np.maximum(passed, 1)
            fraction[ky, kx] = passed.max() / (len(sub) * len(ap))
    return views.reshape(m, m, *lens_shape, 1).astype(np.float32), fraction


def render_microscope_sensor(camera: Camera, scene: MicroscopeScene | None, sensor_shape, *,
                             pixel_samples: int = 2, aperture_samples: int = 3, na_offset=(0.0, 0.0)) -> np.ndarray:
    """Sensor irradiance (H, W) float64 of a microscope capture; ``scene=None``: the white image.

    The lens lattice is rectangular with a lens centred on the sensor centre; pixel (y, x) sits at
    ((x − (W−1)/2), (y − (H−1)/2))·p/R at the lenslets' focal plane (p the camera pixel, R the relay).
    The white image is uniform emission: each pixel holds the fraction of its rays inside the NA
    (``na_offset``: an aperture off the axis, see :func:`object_rays`).

    Parameters
    ----------
    camera : Camera
        A microscope camera.
    scene : MicroscopeScene or None
    sensor_shape : (int, int)
        (H, W) pixels.
    pixel_samples, aperture_samples : int
        Samples per pixel axis and per NA axis.
    na_offset : (float, float)

    Returns
    -------
    ndarray (H, W) float64
    """
    _scope(camera)
    height, width = (int(v) for v in sensor_shape)
    pix = camera.lenslet_pixel_pitch_mm
    sub = pixel_offsets(pixel_samples)
    ap = aperture_offsets_mm("rectangular", camera.mla_pitch_mm, 0.0, aperture_samples)
    yy, xx = np.meshgrid(np.arange(height) - (height - 1) / 2.0, np.arange(width) - (width - 1) / 2.0,
                         indexing="ij")
    points = np.stack([xx.ravel(), yy.ravel()], axis=-1)                          # (P, 2) px
    out = np.zeros(points.shape[0])
    for s in sub:
        p_mm = (points + s) * pix
        lens = np.floor(p_mm / camera.mla_pitch_mm + 0.5) * camera.mla_pitch_mm  # the cell's lens (baffles)
        u = (p_mm - lens) / camera.mla_focal_length_mm
        for a in ap:
            x0, direction, inside = object_rays(camera, lens + a, u, na_offset)
            if scene is None:
                out += inside
            else:
                out += np.where(inside, ray_emission(scene, x0, direction), 0.0)
    return (out / (len(sub) * len(ap))).reshape(height, width)


def render_microscope_capture(camera: Camera, beads, sensor_shape, *, background: float = 0.0, pixel_samples: int = 2,
                              aperture_samples: int = 3, shot_noise_photons=None, read_noise_dn: float = 0.0,
                              exposure: float = 0.8, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A microscope capture of fluorescent beads and its white image, as 16-bit raw DN (what ``lfproc simulate``
    writes for a scene of ``[[bead]]``s).

    The brightest pixel of the beads is at full scale, on a uniform glow of ``background`` × the white image
    (autofluorescence; the white image's brightest pixel at full scale). ``exposure``, ``shot_noise_photons``
    (photons at full scale), ``read_noise_dn`` and ``seed`` as :func:`lfproc.simulate.render`'s.

    Returns
    -------
    capture, white : ndarray, uint16, shape (H, W)
    """
    from ._sensor import radiance_to_dn

    options = {"pixel_samples": pixel_samples, "aperture_samples": aperture_samples}
    white = render_microscope_sensor(camera, None, sensor_shape, **options)
    light = render_microscope_sensor(camera, MicroscopeScene(beads=tuple(beads)), sensor_shape, **options)
    white = white / max(float(white.max()), 1e-30)
    signal = light / max(float(light.max()), 1e-30) + float(background) * white
    capture_rng, white_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(2))
    return (radiance_to_dn(signal, camera, exposure, shot_noise_photons, read_noise_dn, capture_rng),
            radiance_to_dn(white, camera, exposure, shot_noise_photons, read_noise_dn, white_rng))
