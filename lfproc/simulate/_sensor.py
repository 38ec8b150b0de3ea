"""From sensor irradiance to raw DN: the colour filter mosaic, photon and read noise, quantisation."""

from __future__ import annotations

import numpy as np

from ..camera import Camera
from ..errors import LfprocError

#: Rec. 709 luminance weights: how an RGB scene is seen by a monochrome sensor
LUMA_WEIGHTS = (0.2126, 0.7152, 0.0722)
#: the most photons at full scale that shot noise accepts (numpy's Poisson sampler fails near 1e19;
#: far beyond it the noise is below one DN anyway)
MAX_SHOT_NOISE_PHOTONS = 1e12


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
