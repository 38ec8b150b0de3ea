"""The grid file (GRID.json): what ``lfproc calibrate`` and `LensGrid.save` write and `LensGrid.load` reads, and
the `Calibration` of a fitted grid (the file's keys beside the lattice: what the grid was fitted from and what
the fit measured).

One writer and one reader: strict JSON, one top-level key per line, the lattice's keys first
(`lfproc.grid.LensGrid.to_json_dict`: kind, pitch, rotation, origin, size, ``centers_xy_px``, model,
deviation), then the calibration's (`Calibration.KEYS`). The ``centers_xy_px`` (230,000 pairs for a 41 Mpx
sensor, most of the file) follow from the lattice: the reader does not build them (the line `save` writes is
left out before parsing), which saves a command 0.2 s and 25 MB of Python lists. Grid files of every earlier
version load; a damaged ``made_from`` record is refused, not trusted.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field

from .errors import LfprocError

#: how a message tells a Python caller to make a grid file (the commands word it as their command)
MAKE_GRID = "`lfproc.calibrate_white(white, camera).save(path)`"
#: the centres as `write_grid_file` writes them: one line, a list of [x, y] pairs
_CENTRES = '"centers_xy_px": [['


@dataclass(frozen=True, repr=False)
class Calibration:
    """What a lens grid was fitted from and what the fit measured: the keys of a grid file beside the lattice
    (written by `write_grid_file` in this order; docs/calibration.md, docs/inputs.md).

    Attributes
    ----------
    white_image : str or None
        The white image's file (absolute path); None for one given as an array.
    camera : str or None
        The camera file (absolute path); None for a camera built in Python.
    texture_ratio : float or None
        How much the micro images differ from their neighbours (`lfproc.calibrate.white_texture`).
    micro_image_scale, micro_image_scale_sigma : float or None
        The fitted micro image pitch over the camera's lens pitch, ``(d_A + f_s)/d_A``, and its standard error.
    implied_exit_pupil_distance_mm : float or None
        The exit pupil distance d_A that scale implies, mm (``inf``: telecentric within the fit).
    implied_exit_pupil_range_mm : tuple of float or None
        d_A for the scale within its allowance, mm (an end ``inf`` where it reaches telecentric).
    pitch_sigma_px : float or None
        Standard error of the fitted pitch, px.
    made_from : dict or None
        ``{"camera": {...}, "white": {...}, "dark": {...} or None}`` (`lfproc.inputs.made_from`); None in
        grid files written before it was recorded.
    measured_centers_xy_px, inlier : ndarray, shapes (N, 2) and (N,), or None
        Every micro image centre the fit measured (x, y; px) and those it used: in memory only, after a fit.
    """

    white_image: str | None = None
    camera: str | None = None
    texture_ratio: float | None = None
    micro_image_scale: float | None = None
    micro_image_scale_sigma: float | None = None
    implied_exit_pupil_distance_mm: float | None = None
    implied_exit_pupil_range_mm: tuple | None = None
    pitch_sigma_px: float | None = None
    made_from: dict | None = None
    measured_centers_xy_px: np.ndarray | None = field(default=None, compare=False)
    inlier: np.ndarray | None = field(default=None, compare=False)

    #: the keys a grid file holds beside the lattice, in the order written
    KEYS = ("white_image", "camera", "texture_ratio", "micro_image_scale", "micro_image_scale_sigma",
            "implied_exit_pupil_distance_mm", "implied_exit_pupil_range_mm", "pitch_sigma_px", "made_from")

    @property
    def camera_facts(self) -> dict | None:
        """The camera's numbers the grid was fitted for (``made_from["camera"]``), or None."""
        return (self.made_from or {}).get("camera") or None

    @property
    def white_facts(self) -> dict | None:
        """The white image's size, Bayer pattern, path and hash (``made_from["white"]``), or None."""
        return (self.made_from or {}).get("white") or None

    @property
    def dark_facts(self) -> dict | None:
        """The dark frame's path, hash and size (``made_from["dark"]``), or None."""
        return (self.made_from or {}).get("dark") or None

    def to_json_dict(self) -> dict:
        """The grid file's keys beside the lattice (``inf`` as ``null``, see `LensGrid.save`)."""
        return {key: getattr(self, key) for key in self.KEYS}

    @classmethod
    def from_json_dict(cls, data: dict, lattice_pitch_px: float, source: str) -> Calibration:
        """The calibration recorded in a grid file's ``data`` (any version; a damaged ``made_from`` is refused)."""
        made_from = data.get("made_from")
        if made_from is not None and not _valid_made_from(made_from):
            raise LfprocError(f"{source}: its 'made_from' record is damaged; fit the grid again with {MAKE_GRID}")
        span = data.get("implied_exit_pupil_range_mm")
        white, camera = data.get("white_image"), data.get("camera")
        return cls(white_image=white if isinstance(white, str) else None,
                   camera=camera if isinstance(camera, str) else None,
                   texture_ratio=_number(data, "texture_ratio"), micro_image_scale=_number(data, "micro_image_scale"),
                   micro_image_scale_sigma=_number(data, "micro_image_scale_sigma"),
                   implied_exit_pupil_distance_mm=_number(data, "implied_exit_pupil_distance_mm", True),
                   implied_exit_pupil_range_mm=(tuple(_number({"end": v}, "end", True) for v in span)
                                                if isinstance(span, list) and len(span) == 2 else None),
                   pitch_sigma_px=_pitch_sigma(data, lattice_pitch_px), made_from=made_from)

    def __repr__(self) -> str:
        return (f"Calibration(white_image={self.white_image!r}, pitch_sigma_px={self.pitch_sigma_px}, "
                f"texture_ratio={self.texture_ratio}, made_from={'recorded' if self.made_from else None})")


def write_grid_file(path, record: dict) -> None:
    """Write ``record`` (the lattice's and the calibration's keys) as the grid file ``path``, atomically: strict
    JSON (infinity as ``null``), one top-level key per line, each value encoded at once by the json module's C
    encoder (an indented dump of 230,000 centres takes seconds)."""
    from .atomic import json_safe, write_text_atomic

    items = []
    for key, value in record.items():
        safe = value if key == "centers_xy_px" else json_safe(value)  # centres: finite floats already
        items.append(f"  {json.dumps(str(key))}: {json.dumps(safe, allow_nan=False)}")
    write_text_atomic(path, "{\n" + ",\n".join(items) + "\n}\n")


def read_grid_file(path) -> dict:
    """The keys of the grid file ``path`` (``centers_xy_px`` None where written by `write_grid_file`: they follow
    from the lattice); one-line errors naming the file."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except FileNotFoundError:
        raise LfprocError(f"{path}: grid file not found; check the path, or make one with {MAKE_GRID}") from None
    except IsADirectoryError:
        raise LfprocError(f"{path}: is a folder, not a grid file; pass the grid file saved by {MAKE_GRID}") from None
    except (OSError, ValueError) as exc:
        raise LfprocError(f"{path}: not a readable grid file ({getattr(exc, 'strerror', None) or exc}); fit the "
                          f"grid again with {MAKE_GRID}") from None
    start = text.find(_CENTRES)
    end = text.find("]],\n", start)
    try:
        data = json.loads(text[:start] + '"centers_xy_px": null' + text[end + 2:] if 0 <= start < end else text)
    except ValueError:
        try:
            data = json.loads(text)       # a file of another layout, or damaged: the whole text says which
        except ValueError as exc:
            raise LfprocError(f"{path}: not a readable grid file ({exc}); fit the grid again with "
                              f"{MAKE_GRID}") from None
    if not isinstance(data, dict):
        raise LfprocError(f"{path}: not a grid file; fit the grid again with {MAKE_GRID}")
    return data


def _number(data: dict, key: str, null_is_infinity: bool = False) -> float | None:
    """``data[key]`` as a float, else None; ``null`` is infinity where a number may be infinite (a telecentric
    exit pupil: `write_grid_file` writes infinity as ``null``)."""
    value = data.get(key)
    if value is None and null_is_infinity and key in data:
        return math.inf
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _valid_made_from(made_from) -> bool:
    """Whether a ``made_from`` record has the types the checks rely on (a damaged file is refused, not trusted)."""
    if not isinstance(made_from, dict):
        return False
    camera, white, dark = made_from.get("camera"), made_from.get("white"), made_from.get("dark")
    if not isinstance(camera, dict) or not all(_positive(camera.get(k)) for k in ("lens_pitch_px", "micro_image_scale")):
        return False
    if not all(_optional(camera.get(k), str) for k in ("grid", "cfa")):
        return False
    if white is not None and not (isinstance(white, dict) and all(_count(white.get(k)) for k in ("width", "height"))
                                  and _optional(white.get("channels"), int) and all(
                                      _optional(white.get(k), str) for k in ("cfa", "path", "hash"))):
        return False
    return dark is None or (isinstance(dark, dict) and all(_optional(dark.get(k), str) for k in ("path", "hash")))


def _positive(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0


def _count(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value > 0


def _optional(value, kind) -> bool:
    return value is None or (isinstance(value, kind) and not isinstance(value, bool))


def _pitch_sigma(data: dict, pitch_px: float) -> float | None:
    """``pitch_sigma_px`` where recorded; else from ``micro_image_scale_sigma`` (grid files of version 1)."""
    value = data.get("pitch_sigma_px")
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0:
        return float(value)
    scale, sigma = data.get("micro_image_scale"), data.get("micro_image_scale_sigma")
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (scale, sigma)) \
            and scale > 0 and sigma >= 0:
        return float(sigma) / float(scale) * pitch_px
    return None
