"""Object space: the unit, origin and direction in which main optics report where slices and depths lie.

Every result that places something in front of the camera (a slice, a depth, a DOF limit) carries one set
of numbers and the :class:`ObjectSpace` they are in. The space knows how to name, order and print its own
positions, so code that shows or compares positions asks the space instead of asking which optics made it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ObjectSpace:
    """The unit, origin and direction of object-space positions of slices and depths.

    Attributes
    ----------
    unit : str
        The unit in record keys and file tags (``"mm"``, ``"um"``).
    symbol : str
        The unit in human text (``"mm"``, ``"µm"``).
    origin : str
        Where 0 is, and which way is positive (words for labels and sidecars).
    keys : tuple of str
        The record keys of (position, near limit, far limit, depth of field), in this unit.
    per_mm : float
        Units per millimetre (1 or 1000).
    toward_optics : float
        The sign of a step towards the optics: −1 where positions are distances that shrink towards them
        (mm from the sensor), +1 where they grow (z towards an objective).
    letter : str
        The position's symbol in labels (``"d"``, ``"z"``).
    name : str
        How a position is introduced in text: ``""`` (``"206.7 mm"``), ``"z = "`` (``"z = +12.5 µm"``).
    spec : str
        The format of a position in text (``".1f"``, ``"+.4g"``).
    """

    unit: str
    symbol: str
    origin: str
    keys: tuple
    per_mm: float
    toward_optics: float
    letter: str
    name: str = ""
    spec: str = ".1f"

    @property
    def position_key(self) -> str:
        """The record key of a slice's (or a depth's) position: ``distance_mm``, ``z_um``, …."""
        return self.keys[0]

    def named(self, key: str, value):
        """``value`` where ``key`` is one of this space's record keys, else ``None`` (the contract's names of a
        result: ``distance_mm`` of a microscope's slices is ``None``)."""
        return value if key in self.keys else None

    def nearer(self, x, y):
        """Elementwise, the position nearer the optics."""
        return self.toward_optics * np.maximum(self.toward_optics * np.asarray(x), self.toward_optics * np.asarray(y))

    def farther(self, x, y):
        """Elementwise, the position farther from the optics."""
        return self.toward_optics * np.minimum(self.toward_optics * np.asarray(x), self.toward_optics * np.asarray(y))

    def is_nearer(self, x, y):
        """Elementwise, whether ``x`` lies strictly nearer the optics than ``y``."""
        return self.toward_optics * np.asarray(x) > self.toward_optics * np.asarray(y)

    def low_high(self, near, far):
        """(low, high): an interval given by its limits nearer to and farther from the optics, as numbers low
        to high."""
        return (near, far) if self.toward_optics < 0 else (far, near)

    def holds(self, value: float) -> bool:
        """Whether ``value`` is a position of this space: a distance (> 0, infinity included) where positions
        shrink towards the optics, a finite signed depth where they grow; never NaN."""
        return bool(value > 0) if self.toward_optics < 0 else math.isfinite(value)

    def beyond(self, value: float, hair: float = 1e-9) -> float:
        """A ``hair`` farther from the optics than ``value``, against rounding: relative for a distance (which is
        positive: infinity stays infinity), absolute (at least ``hair``) for a signed depth, which crosses 0."""
        if self.toward_optics < 0:
            return value * (1.0 + hair)
        return value - self.toward_optics * hair * max(1.0, abs(value))

    def interval(self, low: float, high: float) -> str:
        """An interval for people, low to high: ``"[335.9 mm, 439.3 mm]"``, ``"[-23.47, -3.07] µm"`` (a named
        coordinate such as z gives its numbers and then its unit)."""
        if self.name:
            return f"[{low:{self.spec}}, {high:{self.spec}}] {self.symbol}"
        return f"[{self.text(low)}, {self.text(high)}]"

    def text(self, value: float) -> str:
        """A position for people: ``"206.7 mm"``, ``"infinity"``, ``"z = +12.5 µm"``."""
        if math.isinf(value):
            return "infinity" if self.name == "" and value > 0 else f"{self.name}{value:+} {self.symbol}"
        return f"{self.name}{value:{self.spec}} {self.symbol}"


#: a photographic camera's object space: millimetres from the sensor (the paper's Eqs. 21, 31)
SENSOR_MM = ObjectSpace("mm", "mm", "from the sensor", ("distance_mm", "near_mm", "far_mm", "dof_mm"), 1.0, -1.0, "d")
#: a microscope's object space: micrometres from the native object plane, positive towards the objective
NATIVE_PLANE_UM = ObjectSpace("um", "µm", "from the native object plane, positive towards the objective",
                              ("z_um", "z_near_um", "z_far_um", "dof_um"), 1000.0, 1.0, "z", "z = ", "+.2f")


class PositionsInSpace:
    """The contract's names of a result's positions (a plain base class of results with ``depth``, ``near``,
    ``far`` and ``space`` attributes): each reads the same array, or is ``None`` where the result is in the other
    space."""

    @property
    def distance_mm(self):
        """``depth`` in mm from the sensor (Eq. 21); ``None`` in another space."""
        return self.space.named("distance_mm", self.depth)

    @property
    def near_mm(self):
        """``near`` in mm from the sensor (Eq. 31); ``None`` in another space."""
        return self.space.named("near_mm", self.near)

    @property
    def far_mm(self):
        """``far`` in mm from the sensor (Eq. 31); ``None`` in another space."""
        return self.space.named("far_mm", self.far)

    @property
    def z_um(self):
        """``depth`` in µm from the native object plane; ``None`` in another space."""
        return self.space.named("z_um", self.depth)

    @property
    def z_near_um(self):
        """``near`` (the larger z, nearer the objective) in µm; ``None`` in another space."""
        return self.space.named("z_near_um", self.near)

    @property
    def z_far_um(self):
        """``far`` (the smaller z) in µm; ``None`` in another space."""
        return self.space.named("z_far_um", self.far)


class SlicesInSpace(PositionsInSpace):
    """:class:`PositionsInSpace` of slices, which also have a depth of field ``dof``."""

    @property
    def dof_mm(self):
        """``dof`` in mm (Eq. 23); ``None`` in another space."""
        return self.space.named("dof_mm", self.dof)

    @property
    def dof_um(self):
        """``dof`` in µm; ``None`` in another space."""
        return self.space.named("dof_um", self.dof)
