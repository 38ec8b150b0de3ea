"""The light-field PSF of a voxel: the objective's field at the lenslets, the lenslet array, the sensor's pixels.

Wave optics of a light-field microscope (Broxton et al., "Wave optics theory and 3-D deconvolution for the
light field microscope", Opt. Express 21(21), 2013), in the plane of the micro lens array (image space,
lengths in µm, light travelling from the sample towards the sensor):

objective and tube lens
    an aplanatic, telecentric 4f system of magnification M: a point at depth z (from the native object
    plane, positive towards the objective) gives at the lenslets the field whose angular spectrum is
    A(κ) = cos(θ)^(−1/2) · exp(−2πi·n·z·cos θ / λ) for |κ| ≤ NA/(M·λ), 0 beyond, with n·sin θ = M·λ·|κ|
    (the Abbe sine condition; κ the image-side spatial frequency in cycles/µm). The amplitude is the
    emission pupil of an aplanatic objective (uniform intensity per solid angle in the sample, the
    pupil height f·sin θ); in Debye's form it is the integral of √cos θ · J₀(2π·n·r·sin θ/(λ·M)) ·
    exp(−2πi·n·z·cos θ/λ) · sin θ dθ over 0 ≤ θ ≤ asin(NA/n) — evaluated here on the FFT grid, so the
    field is exact for a band-limited field on the window (the window holds the point's geometric blur
    with a margin of lenses, :func:`lens_radius`).
lenslets
    a phase mask exp(−iπ·|x − c|²/(λ·f)) with c the nearest lens centre (square cells, no gaps: a
    rectangular array of fill factor 1), f the lenslets' focal length, here the lenslet-to-sensor distance
    f_s (a classical LFM: the sensor in the lenslets' focal plane).
propagation
    the angular spectrum over f_s to the sensor: exp(2πi·f_s·√(1/λ² − |κ|²)) (Rayleigh–Sommerfeld, no
    paraxial approximation; in air).
pixels
    the intensity integrated over each rectified sample (p/m̂ square, centred at (k − c)·p/m̂ from its
    lens centre: exactly the samples of a decoded light field's views), by the midpoint rule on ``q × q``
    sub-samples (:func:`oversampling`: the field sampled finer than its highest frequency needs).

Lenses are at multiples of p; the window holds ``2R + 1`` lenses each way around the voxel's lens.
"""

from __future__ import annotations

import math

import numpy as np

#: lenses of margin around a point's geometric blur in the field's window (diffraction rings, the lenslets'
#: own spread)
MARGIN_LENSES = 2


def image_defocus_um(optics, z_um):
    """Δ = z·M²/n: where the image of a point at depth z lies behind the lenslets (paraxial; µm)."""
    return np.asarray(z_um, dtype=np.float64) * optics.objective_magnification ** 2 / optics.immersion_index


def image_aperture_tangent(optics) -> float:
    """tan θ' of the marginal ray at the lenslets (sin θ' = NA/M)."""
    sine = optics.numerical_aperture / optics.objective_magnification
    return sine / math.sqrt(1.0 - sine * sine)


def blur_radius_lenses(optics, pitch_um: float, z_um) -> np.ndarray:
    """The geometric blur radius at the lenslets of a point at depth ``z_um``, in lens pitches."""
    return np.abs(image_defocus_um(optics, z_um)) * image_aperture_tangent(optics) / pitch_um


def lens_radius(optics, pitch_um: float, z_um: float) -> int:
    """R: the window of a point at ``z_um`` holds lenses −R…R each way (blur, half a lens, the margin)."""
    return int(math.ceil(float(blur_radius_lenses(optics, pitch_um, z_um)) + 0.5)) + MARGIN_LENSES


def oversampling(optics, pitch_um: float, m_hat: int, focal_um: float) -> int:
    """q (odd): sub-samples per rectified sample so that the field after the lenslets is sampled above its
    Nyquist rate: its frequencies reach NA/(M·λ) (the objective) + p/(2·f·λ) (the lenslet's edge)."""
    wavelength = optics.wavelength_nm * 1e-3
    highest = (optics.numerical_aperture / optics.objective_magnification + pitch_um / (2.0 * focal_um)) / wavelength
    q = int(math.ceil(2.0 * highest * pitch_um / m_hat))
    return q + 1 - q % 2


def _frequencies(n: int, step: float) -> np.ndarray:
    return np.fft.fftfreq(n, d=step)


def _cell_offsets(n: int, step: float, pitch: float) -> np.ndarray:
    """Each sample's offset from its nearest lens centre (lenses at multiples of ``pitch``, the window centred
    on a lens; no sample lies on a cell border because the samples per lens are odd)."""
    x = (np.arange(n) - (n - 1) / 2.0) * step
    return x - pitch * np.round(x / pitch)


def voxel_patterns(optics, pitch_um: float, focal_um: float, m_hat: int, oversample: int, z_um: float,
                   offsets_um, radius: int, sample_shift=(0.0, 0.0)) -> np.ndarray:
    """The sensor images of points at depth ``z_um`` and lateral ``offsets_um`` from a lens centre.

    Parameters
    ----------
    optics : lfproc.camera.WaveOptics
    pitch_um, focal_um : float
        The lens pitch p and the lenslet-to-sensor distance f_s (also the lenslets' focal length).
    m_hat : int
        Rectified samples per lens (odd).
    oversample : int
        Sub-samples per sample and axis (odd, :func:`oversampling`).
    z_um : float
        The points' depth from the native object plane, positive towards the objective.
    offsets_um : array (n, 2)
        (y, x) of each point's image at the lenslets, from its lens centre (image space: M × the object
        offset, in the sensor's orientation).
    radius : int
        R: the patterns cover lenses −R…R around the point's lens (:func:`lens_radius`).
    sample_shift : (float, float)
        (y, x) of the central sample off the lens centre, in samples (a decoder's ``view_centre``).

    Returns
    -------
    ndarray, float64, shape (n, m̂, m̂, 2R + 1, 2R + 1)
        ``[i, uy, ux, ky, kx]``: the light of point i in view (uy, ux) of the lens (ky − R, kx − R) lenses
        from its own, each pattern summing to 1 (the light that reaches the sensor).
    """
    from scipy import fft

    wavelength = optics.wavelength_nm * 1e-3
    n_lens = 2 * radius + 1
    size = n_lens * m_hat * oversample
    step = pitch_um / (m_hat * oversample)
    f = _frequencies(size, step)
    kappa2 = f[:, None] ** 2 + f[None, :] ** 2
    sine = wavelength * optics.objective_magnification * np.sqrt(kappa2) / optics.immersion_index
    inside = sine <= optics.numerical_aperture / optics.immersion_index
    cosine = np.sqrt(np.clip(1.0 - sine * sine, 1e-12, None))
    defocus = -2.0 * np.pi * optics.immersion_index * z_um * (cosine - 1.0) / wavelength
    pupil = np.where(inside, np.exp(1j * defocus) / np.sqrt(cosine), 0.0)
    cell = _cell_offsets(size, step, pitch_um)
    lenslet = np.exp(-1j * np.pi * cell ** 2 / (wavelength * focal_um))           # separable: y and x alike
    propagation = np.exp(2j * np.pi * focal_um * np.sqrt(np.clip(1.0 / wavelength ** 2 - kappa2, 0.0, None)))
    shift = np.asarray(sample_shift, dtype=np.float64) * pitch_um / m_hat
    propagation = propagation * np.exp(2j * np.pi * (f[:, None] * shift[0] + f[None, :] * shift[1]))
    centre = (size - 1) / 2.0 * step          # the FFT's origin is sample 0, the window's centre lens is here
    out = np.empty((len(offsets_um), m_hat, m_hat, n_lens, n_lens))
    for i, (dy, dx) in enumerate(np.asarray(offsets_um, dtype=np.float64).reshape(-1, 2)):
        ramp_y = np.exp(-2j * np.pi * f * (centre + dy))
        ramp_x = np.exp(-2j * np.pi * f * (centre + dx))
        field = fft.ifft2(pupil * ramp_y[:, None] * ramp_x[None, :], workers=-1)
        field *= lenslet[:, None]
        field *= lenslet[None, :]
        field = fft.ifft2(fft.fft2(field, workers=-1, overwrite_x=True) * propagation, workers=-1, overwrite_x=True)
        intensity = (field.real ** 2 + field.imag ** 2).reshape(n_lens * m_hat, oversample, n_lens * m_hat, oversample)
        pixels = intensity.sum(axis=(1, 3)).reshape(n_lens, m_hat, n_lens, m_hat)
        out[i] = pixels.transpose(1, 3, 0, 2) / pixels.sum()
    return out
