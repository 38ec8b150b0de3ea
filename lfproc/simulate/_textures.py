"""Plane textures: value t in [0, 1] at a plane point, mapped to ``low + (high − low)·t``.

* :class:`Uniform` — a constant ``value``;
* :class:`Checkerboard` — squares of side ``period_mm / 2`` (one period = two squares);
* :class:`Sinusoid` — ``½ + ½·cos(2π·(x cos θ + y sin θ)/period + φ)``, a grating at angle θ;
* :class:`Noise` — band-limited value noise: random values on a lattice of spacing ``feature_mm``
  (plus half as much at half the spacing), blended with a C² quintic, deterministic for a ``seed``;
* :class:`ImageTexture` — an image file mapped onto ``width_mm`` (height from its aspect ratio),
  centred on ``center_mm``, sampled bilinearly; outside the image the plane is not there.

The numba kernels (:mod:`lfproc.simulate._kernels`) evaluate them from the kind ids below.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ._checks import _check_finite, _check_level, _check_levels, _check_positive

#: texture kind ids shared with the numba kernels of :mod:`lfproc.simulate._kernels`
KIND_UNIFORM, KIND_CHECKER, KIND_SINUSOID, KIND_NOISE, KIND_IMAGE = range(5)


class _LowHigh:
    """Textures whose value t in [0, 1] maps to ``low + (high − low)·t``."""

    def levels(self) -> tuple[float, float]:
        return float(self.low), float(self.high)


@dataclass(frozen=True)
class Uniform:
    """A constant radiance ``value``.

    Attributes
    ----------
    value : float
        The radiance everywhere.
    """

    value: float = 1.0
    kind = KIND_UNIFORM

    def __post_init__(self):
        _check_level(self.value, "value")

    def levels(self) -> tuple[float, float]:
        return float(self.value), float(self.value)


@dataclass(frozen=True)
class Checkerboard(_LowHigh):
    """Checkerboard of period ``period_mm`` (squares of side ``period_mm / 2``): the square
    0 ≤ x, y < period/2 (lower-right of the origin, since y grows downward) is ``low``.

    Attributes
    ----------
    period_mm : float
        One black and one white square, mm.
    low, high : float
        Radiance of the two squares.
    """

    period_mm: float
    low: float = 0.0
    high: float = 1.0
    kind = KIND_CHECKER

    def __post_init__(self):
        _check_positive(self.period_mm, "period_mm")
        _check_levels(self.low, self.high)


@dataclass(frozen=True)
class Sinusoid(_LowHigh):
    """Sinusoidal grating of period ``period_mm`` whose stripes run across the direction ``angle_deg``
    (from +x towards +y); ``phase_deg`` shifts it.

    Attributes
    ----------
    period_mm : float
        Period on the plane, mm.
    angle_deg, phase_deg : float
        Direction of the stripes' normal and phase, degrees.
    low, high : float
        Radiance range.
    """

    period_mm: float
    angle_deg: float = 0.0
    phase_deg: float = 0.0
    low: float = 0.0
    high: float = 1.0
    kind = KIND_SINUSOID

    def __post_init__(self):
        _check_positive(self.period_mm, "period_mm")
        _check_finite(self.angle_deg, "angle_deg")
        _check_finite(self.phase_deg, "phase_deg")
        _check_levels(self.low, self.high)


@dataclass(frozen=True)
class Noise(_LowHigh):
    """Band-limited random texture: value noise with lattice spacing ``feature_mm`` (see the module docstring).

    Attributes
    ----------
    feature_mm : float
        The size of the noise's features on the plane, mm.
    seed : int
    low, high : float
        Radiance range.
    """

    feature_mm: float
    seed: int = 0
    low: float = 0.0
    high: float = 1.0
    kind = KIND_NOISE

    def __post_init__(self):
        _check_positive(self.feature_mm, "feature_mm")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or not 0 <= self.seed < 2**31:
            raise LfprocError(f"noise seed must be an integer in [0, 2^31), got {self.seed!r}")
        _check_levels(self.low, self.high)


@dataclass(frozen=True, eq=False)
class ImageTexture(_LowHigh):
    """An RGB image (``pixels`` shaped (h, w, 3), linear float in [0, 1]) mapped onto ``width_mm``.

    Row 0 of the image is at the smallest y (top of the upright picture), column 0 at the smallest x.
    """

    pixels: np.ndarray
    width_mm: float
    low: float = 0.0
    high: float = 1.0
    source: str = ""
    kind = KIND_IMAGE

    def __post_init__(self):
        _check_positive(self.width_mm, "width_mm")
        _check_levels(self.low, self.high)
        px = np.asarray(self.pixels)
        if px.ndim != 3 or px.shape[2] != 3 or px.shape[0] < 1 or px.shape[1] < 1:
            raise LfprocError(f"image texture {self.source or ''} must be shaped (h, w, 3), got {px.shape}")
        if not np.all(np.isfinite(px)):
            raise LfprocError(f"image texture {self.source or ''} holds NaN or infinite values; fix the image")
        object.__setattr__(self, "pixels", np.ascontiguousarray(px, dtype=np.float32))

    @property
    def height_mm(self) -> float:
        h, w = self.pixels.shape[:2]
        return self.width_mm * h / w


TEXTURES = {"uniform": Uniform, "checkerboard": Checkerboard, "sinusoid": Sinusoid, "grating": Sinusoid,
            "noise": Noise, "image": ImageTexture}


def read_texture_image(path: str, encoding: str = "srgb") -> np.ndarray:
    """Read an image file as linear RGB float32 (h, w, 3) >= 0, through :func:`lfproc.io.read_image`.

    Integer files are scaled to [0, 1] (divided by their type's maximum); float files keep their
    values, so a linear EXR may exceed 1. ``encoding="srgb"`` clips to [0, 1] and undoes the sRGB
    transfer curve. Grey (and grey + alpha) images are replicated to three channels; channels after
    the third (alpha) are dropped.
    """
    from ..io import read_image

    if not os.path.isfile(path):
        raise LfprocError(f"{path}: texture image not found; check the plane's path (relative to the scene file)")
    pixels = read_image(path)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    channels = pixels.shape[2]
    if channels in (1, 2):
        pixels = np.repeat(pixels[:, :, :1], 3, axis=2)
    else:
        pixels = pixels[:, :, :3]
    pixels = np.clip(np.nan_to_num(pixels, nan=0.0, posinf=1.0, neginf=0.0), 0.0, None)
    if encoding == "srgb":
        pixels = srgb_to_linear(np.clip(pixels, 0.0, 1.0))
    return np.ascontiguousarray(pixels, dtype=np.float32)


def srgb_to_linear(values: np.ndarray) -> np.ndarray:
    """The sRGB decoding curve (IEC 61966-2-1)."""
    v = np.asarray(values, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)
