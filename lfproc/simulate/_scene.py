"""Scenes for the simulator: textured planes and a background radiance.

A :class:`Scene` is a tuple of :class:`Plane` objects plus a background radiance. Each plane sits at
``distance_mm`` from the sensor (the paper's distance convention, Eq. 21), carries one texture, an
optional rectangular region and an RGB tint. A ray takes the radiance of the nearest plane whose
region it hits, otherwise the background.

Plane coordinates
-----------------
``(x, y)`` in mm on the plane, the optical axis at ``(0, 0)``, oriented *as seen in the capture*:
x grows with the sensor column and y with the sensor row of the upright picture that refocusing
and viewpoint extraction produce. (The optics invert the picture on the sensor; the renderer
accounts for that, so an image texture appears upright in the decoded views.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from ..errors import LfprocError
from ._checks import _float_tuple
from ._textures import TEXTURES


@dataclass(frozen=True)
class Plane:
    """A fronto-parallel textured plane.

    Parameters
    ----------
    distance_mm : float
        Distance from the sensor (like every distance in lfproc; Eq. 21).
    texture : Uniform, Checkerboard, Sinusoid, Noise or ImageTexture
    region_mm : (x0, x1, y0, y1) or None
        The part of the plane that exists, in plane coordinates (mm, optical axis at 0); ``None`` is
        unbounded (an image texture is always bounded by the image).
    tint : (r, g, b)
        Multiplies the texture value per channel.
    center_mm : (x, y)
        Where the texture's origin (an image's centre) lies on the plane.
    name : str
    """

    distance_mm: float
    texture: object
    region_mm: tuple | None = None
    tint: tuple = (1.0, 1.0, 1.0)
    center_mm: tuple = (0.0, 0.0)
    name: str = ""

    def __post_init__(self):
        where = f"plane {self.name!r}" if self.name else "plane"
        d = self.distance_mm
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d <= 0:
            raise LfprocError(f"{where}: distance_mm must be a finite positive distance from the sensor, got {d!r}")
        if not isinstance(self.texture, tuple(set(TEXTURES.values()))):
            raise LfprocError(f"{where}: texture must be one of {', '.join(sorted(TEXTURES))}")
        if self.region_mm is not None:
            region = _float_tuple(self.region_mm, 4, f"{where}: region_mm")
            if not (region[0] < region[1] and region[2] < region[3]):
                raise LfprocError(f"{where}: region_mm = {list(region)} must be [x0, x1, y0, y1] with x0 < x1 and "
                                  f"y0 < y1")
            object.__setattr__(self, "region_mm", region)
        tint = _float_tuple(self.tint, 3, f"{where}: tint")
        if min(tint) < 0:
            raise LfprocError(f"{where}: tint {list(tint)} must not be negative")
        object.__setattr__(self, "tint", tint)
        object.__setattr__(self, "center_mm", _float_tuple(self.center_mm, 2, f"{where}: center_mm"))

    def describe(self) -> dict:
        """A JSON-ready description (the image pixels are replaced by their source path)."""
        tex = self.texture
        kind = next(name for name, cls in TEXTURES.items() if isinstance(tex, cls))
        params = {f.name: getattr(tex, f.name) for f in fields(tex) if f.name not in ("pixels",)}
        return {"name": self.name, "distance_mm": float(self.distance_mm), "texture": kind, **params,
                "region_mm": None if self.region_mm is None else list(self.region_mm),
                "tint": list(self.tint), "center_mm": list(self.center_mm)}


@dataclass(frozen=True)
class Scene:
    """Planes (in the order given; ties in distance go to the earlier plane) and a background radiance (RGB)."""

    planes: tuple = ()
    background: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        planes = tuple(self.planes)
        for p in planes:
            if not isinstance(p, Plane):
                raise LfprocError(f"scene planes must be Plane objects, got {type(p).__name__}")
        object.__setattr__(self, "planes", planes)
        bg = self.background
        bg = (bg, bg, bg) if isinstance(bg, (int, float)) and not isinstance(bg, bool) else bg
        bg = _float_tuple(bg, 3, "scene background")
        if min(bg) < 0:
            raise LfprocError(f"scene background {list(bg)} must not be negative")
        object.__setattr__(self, "background", bg)
