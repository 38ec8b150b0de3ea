"""Zemax OpticStudio sequential lens files (``.zmx``): the surfaces of a main lens, glasses by catalogue name.

A small reader of the lines that describe a rotationally symmetric lens of spherical surfaces:
``UNIT`` (lens units), ``SURF n`` (a new surface; 0 is the object, the last the image), ``TYPE STANDARD``,
``CURV`` (curvature 1/R), ``DISZ`` (thickness to the next surface, ``INFINITY`` for the object),
``GLAS`` (the glass after the surface: a catalogue name, or ``___BLANK`` with its model index n_d),
``DIAM`` (semi-diameter) and ``STOP``. Everything else (fields, wavelengths, merit functions, solves
already applied to the numbers) is ignored; a surface type other than STANDARD, a mirror or a
conic/aspheric term is refused, since the exact trace assumes spheres.

Glass indices at the camera's wavelength come from optiland's material catalogue (the Schott,
Ohara, Hikari, … data of refractiveindex.info, optional extra ``lfproc[lens]``): only a ``.zmx`` with
catalogue glasses needs it; an inline ``[[main_lens.surfaces]]`` table with indices needs nothing.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..errors import LfprocError
from ._lens import LensPrescription, Surface

#: lens units of a .zmx file in mm
_UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "M": 1000.0}
#: the one-line hint when the optional glass catalogue is missing
LENS_EXTRA_HINT = "pip install 'lfproc[lens]'"


def _read_text(path: str) -> str:
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except FileNotFoundError:
        raise LfprocError(f"{path}: lens prescription not found; give main_lens.prescription relative to the "
                          f"camera file") from None
    except OSError as exc:
        raise LfprocError(f"{path}: cannot read the lens prescription ({exc}); check the path") from None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):      # OpticStudio writes UTF-16 with a byte order mark
        return raw.decode("utf-16")
    return raw.decode("utf-8", errors="replace").lstrip("\ufeff")


def glass_index(name: str, wavelength_nm: float, where: str, catalogs=()) -> float:
    """Refractive index of catalogue glass ``name`` at ``wavelength_nm`` (optiland's catalogue, lazily imported).

    ``catalogs`` are the file's ``GCAT`` names, tried in order (a name such as F5 is in several).
    """
    try:
        from optiland.materials import Material
    except ImportError:
        raise LfprocError(f"{where}: glass {name!r} needs a glass catalogue; {LENS_EXTRA_HINT} (or give the "
                          f"surfaces inline with their indices, [[main_lens.surfaces]])") from None
    import warnings
    error = None
    for catalog in [c.lower() for c in catalogs] + [None]:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                n = Material(name, catalog=catalog).n(wavelength_nm / 1000.0)
            return float(np.asarray(n, dtype=np.float64).ravel()[0])
        except Exception as exc:   # optiland raises plain ValueError/KeyError for unknown names
            error = error or exc
    raise LfprocError(f"{where}: unknown glass {name!r} ({str(error).splitlines()[0][:80]}); use a catalogue "
                      f"name or a model glass (GLAS ___BLANK)")


def read_zmx(path: str | os.PathLike, wavelength_nm: float, object_index: float = 1.0) -> LensPrescription:
    """The lens surfaces of a sequential ``.zmx`` file, indices at ``wavelength_nm``.

    Surface 0 (object) and the last surface (image) are dropped; their thicknesses are not the
    camera's (b_U places the micro lens array, the front focal plane an objective's sample).
    ``object_index``: the medium in front of the first surface (an objective's immersion, from the camera
    file: the object surface's glass is not read).

    Raises
    ------
    LfprocError
        For a missing file, unsupported surfaces, unknown glasses, or (without ``lfproc[lens]``)
        catalogue glasses.
    """
    path = os.fspath(path)
    text = _read_text(path)
    unit = 1.0
    catalogs: list[str] = []
    rows: list[dict] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        tokens = line.split()
        if not tokens:
            continue
        key, args = tokens[0].upper(), tokens[1:]
        if key == "UNIT" and args:
            if args[0].upper() not in _UNITS:
                raise LfprocError(f"{path}: line {lineno}: unknown lens unit {args[0]!r}; use MM, CM, IN or METER")
            unit = _UNITS[args[0].upper()]
        elif key == "GCAT":
            catalogs = list(args)
        elif key == "SURF":
            rows.append(dict(curv=0.0, disz=0.0, glass=None, diam=None, stop=False, line=lineno))
        elif not rows or not line.startswith("  "):
            continue
        elif key == "TYPE" and args and args[0].upper() not in ("STANDARD",):
            raise LfprocError(f"{path}: line {lineno}: surface type {args[0]} is not supported (only spherical "
                              f"STANDARD surfaces); convert the lens or give its surfaces inline")
        elif key == "CURV" and args:
            rows[-1]["curv"] = _number(args[0], path, lineno)
        elif key == "DISZ" and args:
            rows[-1]["disz"] = math.inf if args[0].upper().startswith("INF") else _number(args[0], path, lineno)
        elif key == "CONI" and args and _number(args[0], path, lineno) != 0.0:
            raise LfprocError(f"{path}: line {lineno}: conic surfaces are not supported (only spheres); give the "
                              f"surfaces inline or use a spherical design")
        elif key == "GLAS" and args:
            if args[0].upper() == "MIRROR":
                raise LfprocError(f"{path}: line {lineno}: mirrors are not supported; a main lens here refracts only")
            rows[-1]["glass"] = args
        elif key == "DIAM" and args:
            rows[-1]["diam"] = _number(args[0], path, lineno)
        elif key == "STOP":
            rows[-1]["stop"] = True
    if len(rows) < 3:
        raise LfprocError(f"{path}: not a sequential Zemax lens file (no SURF lines of a lens); pass a .zmx file")
    lens_rows = rows[1:-1]
    surfaces = []
    for k, row in enumerate(lens_rows, 1):
        index = 1.0
        if row["glass"] is not None:
            name = row["glass"][0]
            if name.upper() == "___BLANK":       # a model glass: GLAS ___BLANK 1 0 nd vd ...
                if len(row["glass"]) < 4:
                    raise LfprocError(f"{path}: line {row['line']}: model glass without an index")
                index = _number(row["glass"][3], path, row["line"])
            else:
                index = glass_index(name, wavelength_nm, f"{path}: surface {k}", catalogs)
        curv = row["curv"] / unit
        surfaces.append(Surface(math.inf if curv == 0.0 else 1.0 / curv, row["disz"] * unit, index,
                                None if row["diam"] is None else row["diam"] * unit, row["stop"]))
    if rows[0]["stop"] or rows[-1]["stop"]:
        raise LfprocError(f"{path}: the stop is on the object or image surface; put it on a lens surface")
    return LensPrescription(tuple(surfaces), wavelength_nm, path, object_index)


def _number(token: str, path: str, lineno: int) -> float:
    try:
        return float(token)
    except ValueError:
        raise LfprocError(f"{path}: line {lineno}: {token!r} is not a number; fix the lens file") from None
