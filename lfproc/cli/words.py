"""The commands' words for the library's: a message the library words for a Python caller (``white=``,
``aperture=2.8``) is reworded here, where a command reports it, with the flags its user typed (``--white
WHITE``, ``--aperture 2.8``).

The library names an argument as ``name=`` in four forms, each with its command-line reading:

=====================  ==========================  ===========================================
library (Python)       command                     e.g.
=====================  ==========================  ===========================================
``name=``              the flag                    ``decode with camera=`` → ``--camera``
``name=...``           the flag and its metavar    ``pass white=...`` → ``--white WHITE``
``name=VALUE``         the flag and the value      ``dark=d.tif`` → ``--dark d.tif``
``name=True``          the flag (a switch)         ``white_is_white=True`` → ``--white-is-white``
=====================  ==========================  ===========================================

A few messages name a command's positional argument (``WHITE`` of ``lfproc calibrate``) where Python
has a keyword, or tell a Python caller how to make a lens grid (``lfproc.calibrate_white``) where a command's
user runs ``lfproc calibrate``: :data:`PHRASES` words those whole, before the table is applied.
"""

from __future__ import annotations

import re

#: Python argument -> (the commands' flag, or None for a positional argument; the metavar)
FLAGS = {
    "aperture": ("--aperture", "F"),
    "background": ("--background", "B"),
    "camera": ("--camera", "CAM.toml"),
    "capture": (None, "RAW"),
    "dark": ("--dark", "DARK"),
    "decode_interpolation": ("--decode-interpolation", "METHOD"),
    "demosaic": ("--demosaic", "METHOD"),
    "depth_range_mm": ("--depth-range", "NEAR_MM:FAR_MM"),
    "distance_mm": ("--at", "MM"),
    "focus_distance_mm": ("--focus-distance", "MM"),
    "gap": ("--gap", "G"),
    "grid": ("--calib", "GRID.json"),
    "inside_aperture": ("--inside-aperture", None),
    "interpolation": ("--interpolation", "METHOD"),
    "iterations": ("--iterations", "N"),
    "min_confidence": ("--min-confidence", "C"),
    "outdir": ("-o", "OUTDIR"),
    "port": ("--port", "PORT"),
    "scheduler": ("--scheduler", "ADDRESS"),
    "superres": ("--superres", "S"),
    "tolerance": ("--tolerance", "T"),
    "white": ("--white", "WHITE"),
    "white_dir": ("--white-dir", "DIR"),
    "white_is_white": ("--white-is-white", None),
    "workers": ("--workers", "N"),
    "z_range_um": ("--z-range", "Z0:Z1"),
    "z_um": ("--z-range", "Z0:Z1"),
}

#: whole phrases the commands word otherwise than the table would (their positional WHITE; a warning that
#: also gave the Python spelling before the library spoke Python)
PHRASES = {
    "lfproc.calibrate_white(white, camera).save(path)": "lfproc calibrate WHITE --camera CAM -o GRID.json",
    "lfproc.read_light_field(...).save(path)": "'lfproc decode'",
    "check the grid (lfproc.calibrate_white)": "check the grid (lfproc calibrate)",
    "(a LensGrid from lfproc.calibrate_white, or its saved file)": "(from lfproc calibrate)",
    "as white=, or pass white_is_white=True": "as WHITE, or pass --white-is-white",
    "pass the white image as white= and": "pass the white image as WHITE (--white) and",
    "say so with white_is_white=True": "say so with --white-is-white (white_is_white=True)",
}

_WORDS = re.compile("|".join(re.escape(p) for p in PHRASES) + r"|(?<![\w./=-])("
                    + "|".join(sorted(FLAGS, key=len, reverse=True)) + r")=(\.\.\.|True\b)?")


def command_words(message: str) -> str:
    """``message`` (worded for a Python caller) with each argument named as the commands name it."""
    return _WORDS.sub(_flag, message)


def _flag(match) -> str:
    if match.group(1) is None:
        return PHRASES[match.group(0)]
    flag, metavar = FLAGS[match.group(1)]
    form = match.group(2)
    rest = match.string[match.end():match.end() + 1]
    if form == "...":
        return metavar if flag is None else f"{flag} {metavar}"
    if form == "True":
        return flag
    if flag is None:
        return metavar
    if rest and not rest.isspace() and rest not in ",;)":
        return f"{flag} "        # a value follows: ``--dark d.tif``
    return flag
