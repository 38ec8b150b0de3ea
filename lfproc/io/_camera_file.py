"""`read_camera`: the one reader of the files that describe a camera (a camera TOML, napari-LF's
``metadata.txt``, a Lytro file's metadata)."""

from __future__ import annotations

import os

from ..camera import Camera
from ..errors import LfprocError, warn
from ._checks import existing_file


def read_camera(path: str | os.PathLike) -> Camera:
    """The camera a file describes, whichever of the three kinds of file it is.

    * a camera file (TOML, ARCHITECTURE.md's camera file format): as `Camera.from_toml`;
    * napari-LF's ``metadata.txt`` (JSON with a ``"calibrate"`` table): a light-field microscope, as
      ``lfproc camera metadata.txt`` writes it (docs/microscope.md), m̂ left to the measured micro image
      pitch of the white image it is decoded with;
    * a Lytro file (a ``.lfr``/``.lfp`` capture, white image or processed picture with camera metadata,
      or ``NAME.raw`` with ``NAME.txt``/``.json``): the camera of its metadata, as ``lfproc camera`` writes
      it, the main lens focused at infinity (warned: the metadata has no focus distance).

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    Camera
        With ``source`` the file and ``provenance`` saying where each number came from.

    Raises
    ------
    LfprocError
        A missing or unreadable file, one of none of these kinds, or one whose numbers are missing or
        impossible (one line naming the file and the key).

    Warns
    -----
    LfprocWarning
        A Lytro file's camera: its focus distance is assumed (infinity); ``lfproc.focused_at(camera, MM)``
        sets the real one.
    """
    from ._lytro_camera import lytro_camera
    from ._lytro_picture_open import camera_metadata
    from ._lytro_read import is_lytro_file
    from ._napari_metadata import is_napari_metadata, napari_camera

    path = existing_file(path)
    if is_lytro_file(path):
        camera = lytro_camera(camera_metadata(path)).camera
        warn(f"{path}: camera from its metadata, main lens focused at infinity (the metadata has no focus "
             f"distance); lfproc.focused_at(camera, MM) sets where it focused")
        return camera
    if is_napari_metadata(path):
        return napari_camera(path)[0]
    with open(path, "rb") as fh:
        if fh.read(64).lstrip().startswith(b"{"):
            raise LfprocError(f"{path}: a JSON file, but not napari-LF's metadata (no \"calibrate\" table with "
                              f"ulens_pitch) nor a Lytro raw's metadata (read through its NAME.raw); pass a camera "
                              f"TOML file, napari-LF's metadata.txt or a Lytro file")
    return Camera.from_toml(path)
