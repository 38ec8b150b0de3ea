"""`read_capture`: pick the reader for a capture or white image by what the file is."""

from __future__ import annotations

import os

from ..errors import LfprocError
from ._capture import Capture
from ._checks import _NotThisFormat, existing_file, unreadable_reasons

#: extensions tried with LibRaw (rawpy) first; everything else goes to OpenImageIO first
RAW_EXTENSIONS = frozenset({
    ".3fr", ".ari", ".arw", ".bay", ".cap", ".cr2", ".cr3", ".crw", ".dcr", ".dcs", ".dng", ".drf",
    ".eip", ".erf", ".fff", ".gpr", ".iiq", ".k25", ".kdc", ".mdc", ".mef", ".mos", ".mrw", ".nef",
    ".nrw", ".orf", ".pef", ".ptx", ".pxn", ".r3d", ".raf", ".raw", ".rw2", ".rwl", ".rwz", ".sr2",
    ".srf", ".srw", ".x3f",
})


def read_capture(path: str | os.PathLike, camera=None) -> Capture:
    """Read a sensor capture as a linear float32 `Capture`.

    Lytro files (``.lfp``/``.lfr`` containers, any case, or any file with the container magic;
    ``NAME.raw`` with ``NAME.txt``/``NAME.json`` beside it) are unpacked with their own per-channel
    levels and Bayer layout (`lfproc.io.read_lytro_metadata`); a processed Lytro picture without raw
    data is refused. Camera raws go through LibRaw: the visible raw mosaic, the per-channel black
    levels of the file subtracted, divided by (white level − black); the camera file's levels are
    ignored for them (the contract: LibRaw raws carry their own). Other files go through
    OpenImageIO: 8/16-bit integer data keeps its digital numbers, from which the camera's black level
    is subtracted and the result divided by (white − black), with ``camera.raw_levels(type max)``:
    a white level the camera file does not give is the file's own maximum (255 for 8-bit, 65535 for
    16-bit), and one given above that maximum is an error. Float files (EXR, float TIFF) are taken
    as already linear (black 0, white 1). Single-channel files take their CFA from ``camera.cfa``
    ("none" without a camera); files with colour channels give ``(H, W, 3)`` data (alpha dropped)
    and CFA "none".

    The reader is chosen by extension and falls back to the other one when the first does not
    recognise the content, except for ``.dng``: OpenImageIO would read a DNG as a plain TIFF
    without its levels and CFA, so a DNG LibRaw rejects is an error. No brightening, gamma or
    demosaicing happens here.

    Parameters
    ----------
    path : str or os.PathLike
    camera : lfproc.camera.Camera, optional
        Supplies ``cfa``, ``black_level`` and ``white_level`` for files without their own.

    Raises
    ------
    LfprocError
        Missing, empty, truncated, corrupt or unreadable files, unsupported formats (X-Trans and
        other non-Bayer CFAs, unknown Lytro packings), zero-size images, NaN/inf in float files,
        impossible levels, processed Lytro pictures.
    """
    from ._libraw import read_libraw_capture
    from ._lytro_read import is_lytro_file, read_lytro_capture
    from ._oiio import read_oiio_capture

    path = existing_file(path)
    if is_lytro_file(path):
        return read_lytro_capture(path, camera)
    extension = os.path.splitext(path)[1].lower()
    readers = (read_libraw_capture, read_oiio_capture)
    if extension == ".dng":
        # a DNG is also a TIFF: OpenImageIO would read it without its levels and CFA, silently wrong
        readers = (read_libraw_capture,)
    elif extension not in RAW_EXTENSIONS:
        readers = readers[::-1]
    reasons = []
    hint = " (a Lytro .raw needs its metadata NAME.txt or NAME.json beside it)" if extension == ".raw" else ""
    for index, reader in enumerate(readers):
        try:
            if reader is read_libraw_capture and index > 0:
                return reader(path, camera, fallback=True)   # the extension chose another reader
            return reader(path, camera)
        except _NotThisFormat as exc:
            reasons.append(str(exc))
        except LfprocError as exc:
            raise LfprocError(f"{exc.marked}{hint}") from None
    raise LfprocError(f"{path}: not a readable image or camera raw{unreadable_reasons(reasons)}; "
                      f"pass a camera raw (DNG, CR2, NEF, …), a Lytro .lfr/.lfp, a TIFF, PNG or EXR file{hint}")
