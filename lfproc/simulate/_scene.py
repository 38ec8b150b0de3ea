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

Tilted planes
-------------
``tilt_deg = (tx, ty)`` turns a plane about its centre point, the point on the optical axis at
``distance_mm``: first by ``ty`` about the x axis (depth then grows with y), then by ``tx`` about the
y axis (depth grows with x). With depth d measured from the sensor, the plane's own axes and normal
in (x, y, d) are::

    e1 = (cos tx, 0, sin tx)
    e2 = (−sin ty·sin tx, cos ty, sin ty·cos tx)
    n  = (−cos ty·sin tx, −sin ty, cos ty·cos tx)

so its depth at the lateral point (x, y) is ``distance_mm + x·tan tx + y·tan ty / cos tx``
(:meth:`Plane.distance_at`). Textures and ``region_mm`` use the plane's own coordinates
(along e1 and e2, the centre point at (0, 0)): a tilted card keeps its printed size. An untilted
plane has e1 = x, e2 = y.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ..errors import LfprocError
from ._checks import _float_tuple
from ._textures import TEXTURES

#: the steepest tilt a plane may have, in degrees (beyond it a plane runs almost along the rays)
MAX_TILT_DEG = 80.0


@dataclass(frozen=True)
class Plane:
    """A textured plane, fronto-parallel unless tilted.

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
    tilt_deg : (tx, ty)
        Tilt about the plane's centre point in degrees, each in (−80, 80): ``tx`` about the y axis
        (positive: farther towards +x), ``ty`` about the x axis (positive: farther towards +y); see
        the module docstring for the exact frame.
    """

    distance_mm: float
    texture: object
    region_mm: tuple | None = None
    tint: tuple = (1.0, 1.0, 1.0)
    center_mm: tuple = (0.0, 0.0)
    name: str = ""
    tilt_deg: tuple = (0.0, 0.0)

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
        tilt = _float_tuple(self.tilt_deg, 2, f"{where}: tilt_deg")
        if max(abs(v) for v in tilt) >= MAX_TILT_DEG:
            raise LfprocError(f"{where}: tilt_deg {list(tilt)} must lie within ±{MAX_TILT_DEG:g} degrees")
        object.__setattr__(self, "tilt_deg", tilt)

    @property
    def tilted(self) -> bool:
        """True when either tilt angle is not zero."""
        return self.tilt_deg != (0.0, 0.0)

    def frame(self) -> np.ndarray:
        """The plane's axes e1, e2 and normal n as rows of a (3, 3) array, in (x, y, depth) coordinates."""
        tx, ty = (math.radians(v) for v in self.tilt_deg)
        return np.array([[math.cos(tx), 0.0, math.sin(tx)],
                         [-math.sin(ty) * math.sin(tx), math.cos(ty), math.sin(ty) * math.cos(tx)],
                         [-math.cos(ty) * math.sin(tx), -math.sin(ty), math.cos(ty) * math.cos(tx)]])

    def distance_at(self, x_mm, y_mm):
        """Depth (distance from the sensor, mm) of the plane at the lateral point (x, y) in plane coordinates.

        ``distance_mm + x·tan tx + y·tan ty / cos tx``; broadcasts over numpy arrays. Unbounded: the
        plane's ``region_mm`` is not applied.
        """
        _, _, (nx, ny, nz) = self.frame()
        x, y = np.asarray(x_mm, dtype=np.float64), np.asarray(y_mm, dtype=np.float64)
        return self.distance_mm - (nx * x + ny * y) / nz

    def describe(self) -> dict:
        """A JSON-ready description (the image pixels are replaced by their source path)."""
        tex = self.texture
        kind = next(name for name, cls in TEXTURES.items() if isinstance(tex, cls))
        params = {f.name: getattr(tex, f.name) for f in fields(tex) if f.name not in ("pixels",)}
        return {"name": self.name, "distance_mm": float(self.distance_mm), "texture": kind, **params,
                "region_mm": None if self.region_mm is None else list(self.region_mm),
                "tint": list(self.tint), "center_mm": list(self.center_mm),
                **({"tilt_deg": list(self.tilt_deg)} if self.tilted else {})}


@dataclass(frozen=True)
class Scene:
    """Planes (in the order given; ties in distance go to the earlier plane) and a background radiance (RGB).

    Attributes
    ----------
    planes : tuple of Plane
        Textured planes, fronto-parallel (the nearest hides the others; ties go to the earlier plane).
    background : tuple of float
        The radiance (RGB) where no plane is hit.
    """

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
