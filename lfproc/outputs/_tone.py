"""Tone mapping of linear images to 8-bit sRGB for display (previews only; the data stay linear).

The exposure is one linear stretch for a whole set of images (every frame of an animation, every
slice and view of a viewer page), so that they compare: the set's 0.5th percentile maps to black and
its 99.5th to white (all channels pooled, so colour balance is kept), then the sRGB transfer curve
(IEC 61966-2-1) encodes the result in 8 bits. Without the black point, linear light fields of
low-contrast scenes (a wall of reflectance 0.25–0.9 with views averaged) look washed out after the
sRGB curve; with it they use the whole display range. Pass explicit ``black``/``white`` for a fixed
exposure instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: default percentiles of the exposure (of all pixel values of the set, channels pooled)
LOW_PERCENTILE, HIGH_PERCENTILE = 0.5, 99.5
#: values the percentiles are estimated from (an even subsample of larger sets; exact for smaller)
_PERCENTILE_SAMPLES = 1 << 21
_LUT_SIZE = 1 << 14  # linear -> sRGB lookup: 16384 steps keep the 8-bit result within 0.2 levels of exact


def _srgb_lut() -> np.ndarray:
    x = np.linspace(0.0, 1.0, _LUT_SIZE)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.round(encoded * 255.0).astype(np.uint8)


_SRGB_LUT = _srgb_lut()


@dataclass(frozen=True)
class ToneMap:
    """Linear value v → 8-bit sRGB: ``srgb(clip((v − black) / (white − black), 0, 1))``.

    Attributes
    ----------
    black, white : float
        The linear values shown as black and as white (``white > black``).
    """

    black: float
    white: float

    def __post_init__(self):
        if not (np.isfinite(self.black) and np.isfinite(self.white) and self.white > self.black):
            raise ValueError(f"tone map needs finite black < white, got {self.black}, {self.white}")

    @classmethod
    def for_images(cls, images, low_percentile: float = LOW_PERCENTILE,
                   high_percentile: float = HIGH_PERCENTILE) -> "ToneMap":
        """The exposure of a set of linear images: its low percentile → black, its high one → white.

        A flat set (high ≤ low) gets ``white = black + 1`` (or black 0 and white = its value if
        positive), so a uniform image shows its grey rather than failing.
        """
        values = np.asarray(images).reshape(-1)
        if values.size > _PERCENTILE_SAMPLES:
            values = values[:: values.size // _PERCENTILE_SAMPLES]
        values = values[np.isfinite(values)]
        if values.size == 0:
            return cls(0.0, 1.0)
        low, high = (float(v) for v in np.percentile(values, [low_percentile, high_percentile]))
        if high > low:
            return cls(low, high)
        return cls(0.0, high) if high > 0 else cls(low, low + 1.0)

    def __call__(self, image) -> np.ndarray:
        """The 8-bit sRGB image (same shape, uint8) of a linear ``image``; NaN shows as black."""
        scaled = (np.asarray(image, dtype=np.float32) - np.float32(self.black)) * np.float32(
            (_LUT_SIZE - 1) / (self.white - self.black))
        index = np.nan_to_num(scaled, nan=0.0, posinf=_LUT_SIZE - 1, neginf=0.0)
        np.clip(index, 0, _LUT_SIZE - 1, out=index)
        return _SRGB_LUT[(index + 0.5).astype(np.int32)]

    def describe(self) -> str:
        """One line for captions and metadata."""
        return (f"linear {self.black:.4g} -> black, {self.white:.4g} -> white, then the sRGB curve "
                f"(percentiles {LOW_PERCENTILE} and {HIGH_PERCENTILE} of the set unless given)")
