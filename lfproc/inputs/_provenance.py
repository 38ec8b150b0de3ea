"""What a grid file was made from (GRID.json's ``made_from``), and reading it back.

``lfproc calibrate`` (and the in-process calibration of ``--white``) records the camera's pixel pitch,
lens pitch, lattice kind, m̂ and micro image scale, the white image's size, Bayer pattern and content
hash, the dark frame (path and hash) if one was subtracted, and the calibration's pitch uncertainty
(``pitch_sigma_px``). Grid files written before this (no ``made_from``) still load; they are checked
as far as what they hold allows (`lfproc.inputs.check_grid_fits_camera`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

from ..errors import LfprocError


@dataclass(frozen=True)
class GridRecord:
    """A grid file as read: the lattice plus what it was made from.

    Attributes
    ----------
    path : str
        The grid file.
    grid : lfproc.grid.LensGrid
    white_image : str or None
        The white image it was calibrated from (absolute path, as recorded).
    made_from : dict or None
        ``{"camera": {...}, "white": {...}, "dark": {...} or None}``; ``None`` for older grid files.
    pitch_sigma_px : float or None
        Standard error of the fitted pitch (px); ``None`` where the file does not say.
    """

    path: str
    grid: object
    white_image: str | None = None
    made_from: dict | None = None
    pitch_sigma_px: float | None = None

    @property
    def camera_facts(self) -> dict | None:
        return (self.made_from or {}).get("camera") or None

    @property
    def white_facts(self) -> dict | None:
        return (self.made_from or {}).get("white") or None

    @property
    def dark_facts(self) -> dict | None:
        return (self.made_from or {}).get("dark") or None


def read_grid_record(path: str) -> GridRecord:
    """Read a GRID.json written by ``lfproc calibrate`` (any version); one-line errors."""
    from ..grid import LensGrid

    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except FileNotFoundError:
        raise LfprocError(f"{path}: grid file not found; run 'lfproc calibrate WHITE --camera CAM -o {path}'") \
            from None
    except IsADirectoryError:
        raise LfprocError(f"{path}: is a folder, not a grid file; pass the GRID.json written by lfproc calibrate") \
            from None
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        raise LfprocError(f"{path}: not a readable grid file ({reason}); run lfproc calibrate again") from None
    if not isinstance(data, dict):
        raise LfprocError(f"{path}: not a grid file written by 'lfproc calibrate'; run lfproc calibrate again")
    grid = LensGrid.from_json_dict(data, source=path)
    made_from = data.get("made_from")
    if made_from is not None and not _valid_made_from(made_from):
        raise LfprocError(f"{path}: its 'made_from' record is damaged; run lfproc calibrate again")
    white = data.get("white_image")
    return GridRecord(path, grid, white if isinstance(white, str) else None, made_from,
                      _pitch_sigma(data, grid))


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
    return dark is None or (isinstance(dark, dict) and all(isinstance(dark.get(k), str) for k in ("path", "hash")))


def _positive(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0


def _count(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value > 0


def _optional(value, kind) -> bool:
    return value is None or (isinstance(value, kind) and not isinstance(value, bool))


def _pitch_sigma(data: dict, grid) -> float | None:
    """``pitch_sigma_px`` where recorded; else from ``micro_image_scale_sigma`` (grid files of version 1)."""
    for key, factor in (("pitch_sigma_px", 1.0),):
        value = data.get(key)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0:
            return float(value) * factor
    scale, sigma = data.get("micro_image_scale"), data.get("micro_image_scale_sigma")
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (scale, sigma)) \
            and scale > 0 and sigma >= 0:
        return float(sigma) / float(scale) * grid.pitch_px
    return None


def made_from(camera, white_facts, white_hash: str, dark_facts=None, dark_hash: str | None = None) -> dict:
    """The ``made_from`` record of a calibration (module docstring).

    Parameters
    ----------
    camera : lfproc.Camera
    white_facts, dark_facts : lfproc.inputs.ImageFacts (dark optional)
    white_hash, dark_hash : str
        `file_hash` of the files.
    """
    import os

    from ..geometry import micro_image_scale

    return {
        "camera": {"source": os.path.abspath(camera.source) if camera.source else None,
                   "pixel_pitch_mm": camera.pixel_pitch_mm, "lens_pitch_mm": camera.mla_pitch_mm,
                   "lens_pitch_px": camera.pitch_px, "grid": camera.grid, "m_hat": camera.m_hat, "cfa": camera.cfa,
                   "micro_image_scale": float(micro_image_scale(camera))},
        "white": {"path": os.path.abspath(white_facts.path), "width": white_facts.width,
                  "height": white_facts.height, "cfa": white_facts.cfa, "channels": white_facts.channels,
                  "hash": white_hash},
        "dark": None if dark_facts is None else {"path": os.path.abspath(dark_facts.path), "hash": dark_hash,
                                                 "width": dark_facts.width, "height": dark_facts.height},
    }
