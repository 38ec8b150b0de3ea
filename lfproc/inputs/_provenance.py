"""What a lens grid was made from (the ``made_from`` record of its `lfproc.grid.Calibration`).

Every grid fitting (`lfproc.calibrate_white`) records the camera's pixel pitch, lens pitch, lattice kind, m̂
and micro image scale, the white image's size, Bayer pattern and content hash, and the dark frame (path and
hash) if one was subtracted; `LensGrid.save` writes it into the grid file and `LensGrid.load` reads it back.
Grid files written before this (no ``made_from``) still load; they are checked as far as what they hold allows
(`lfproc.inputs.check_grid_fits_camera`).
"""

from __future__ import annotations

import os


def made_from(camera, white_facts, white_hash: str, dark_facts=None, dark_hash: str | None = None) -> dict:
    """The ``made_from`` record of a calibration (module docstring).

    Parameters
    ----------
    camera : lfproc.Camera
    white_facts, dark_facts : lfproc.inputs.ImageFacts (dark optional)
    white_hash, dark_hash : str or None
        `file_hash` of the files; None for an image given as an array (then its path is None too).
    """
    from ..geometry import micro_image_scale

    def path(facts, digest):
        return os.path.abspath(facts.path) if digest is not None else None

    return {
        "camera": {"source": os.path.abspath(camera.source) if camera.source else None,
                   "pixel_pitch_mm": camera.pixel_pitch_mm, "lens_pitch_mm": camera.mla_pitch_mm,
                   "lens_pitch_px": camera.pitch_px, "grid": camera.grid, "m_hat": camera.m_hat, "cfa": camera.cfa,
                   "micro_image_scale": float(micro_image_scale(camera))},
        "white": {"path": path(white_facts, white_hash), "width": white_facts.width,
                  "height": white_facts.height, "cfa": white_facts.cfa, "channels": white_facts.channels,
                  "hash": white_hash},
        "dark": None if dark_facts is None else {"path": path(dark_facts, dark_hash), "hash": dark_hash,
                                                 "width": dark_facts.width, "height": dark_facts.height},
    }
