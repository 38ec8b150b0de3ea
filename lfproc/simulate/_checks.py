"""Argument validators shared by the scene model, the scene file parser and the renderer.

Each raises :class:`lfproc.LfprocError` with one line naming the value and what it must be.
"""

from __future__ import annotations

import math

import numpy as np

from ..camera import Camera, MainLens
from ..errors import LfprocError
from ._sensor import MAX_SHOT_NOISE_PHOTONS


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(value, what: str) -> float:
    if not _is_number(value) or not math.isfinite(value):
        raise LfprocError(f"{what} must be a finite number, got {value!r}")
    return float(value)


def _integer(value, what: str, minimum: int) -> int:
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise LfprocError(f"{what} must be an integer >= {minimum}, got {value!r}")
    return value


def _number_list(value, n: int, what: str) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise LfprocError(f"{what} must be a list of {n} numbers, got {value!r}")
    return [_number(v, what) for v in value]


def _float_tuple(value, n: int, what: str) -> tuple:
    return tuple(_number_list(list(value) if isinstance(value, (list, tuple, np.ndarray)) else value, n, what))


def _check_positive(value, what: str) -> None:
    if not _is_number(value) or not math.isfinite(value) or value <= 0:
        raise LfprocError(f"texture {what} must be a finite positive number of mm, got {value!r}")


def _check_finite(value, what: str) -> None:
    if not _is_number(value) or not math.isfinite(value):
        raise LfprocError(f"texture {what} must be a finite number, got {value!r}")


def _check_level(value, what: str) -> None:
    if not _is_number(value) or not math.isfinite(value) or value < 0:
        raise LfprocError(f"texture {what} must be a radiance >= 0, got {value!r}")


def _check_levels(low, high) -> None:
    _check_level(low, "low")
    _check_level(high, "high")


def _require_f_number(camera: Camera) -> None:
    # the tracer places a main lens's stop and principal planes at distances from the sensor: a main lens's own
    # renderer (a microscope has its own, _microscope.py)
    if not isinstance(camera.main_optics, MainLens):
        raise LfprocError(f"{camera.source or 'camera'}: this renderer traces a main lens ([main_lens]), its stop and "
                          f"planes at distances from the sensor; this camera's optics are a "
                          f"{camera.main_optics.describe()}")
    if camera.main_optics.f_number is None:
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
