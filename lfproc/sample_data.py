"""Where the bundled samples are: inside the installed package, wherever pip put it.

``lfproc info --samples`` prints the same list (the commands' words for :func:`sample_path`'s error). In a
source checkout ``samples/`` at the top links to the same folder (``lfproc/samples``).
"""

from __future__ import annotations

from pathlib import Path

from .errors import LfprocError

#: the package's sample folder
SAMPLES_DIR = Path(__file__).resolve().parent / "samples"

#: what each bundled sample is, by its path relative to :data:`SAMPLES_DIR`
SAMPLES = {
    "sample/capture.png": "simulated RGGB capture (the demo's): 9 um pixels, 100 um lenses, planes at 380/650/1200 mm",
    "sample/white.png": "its white image (lfproc calibrate, --white)",
    "sample/camera.toml": "its camera file (--camera)",
    "sample/scene.toml": "the scene it was rendered from (lfproc simulate)",
    "sample/ground_truth.json": "its lens grid and plane distances, as rendered",
    "microscope/beads.toml": "three fluorescent beads under a light-field microscope (lfproc simulate, then "
                             "lfproc deconvolve: docs/deconvolution.md)",
    "cameras/": "the paper's set-ups (Table 2-4), an Illum-like camera and a real Double Gauss (its surfaces)",
    "lenses/double-gauss-f100.zmx": "a Double Gauss of f = 100 mm as a Zemax lens file (docs/real-lens.md)",
    "lytro/IMG_0001.lfr": "a simulated Lytro Illum-like capture (container with packed 10-bit raw)",
    "lytro/caldata/": "its camera's calibration folder (--white-dir)",
}


def sample_path(name: str = "") -> Path:
    """The absolute path of a bundled sample, e.g. ``sample_path("sample/capture.png")``.

    Raises
    ------
    LfprocError
        For a name that is not in the package (the message lists what is).

    Parameters
    ----------
    name : str
        A path inside the bundled samples (``""``: their folder).

    Returns
    -------
    pathlib.Path
    """
    path = SAMPLES_DIR / name
    if not path.exists():
        raise LfprocError(f"no bundled sample {name!r}; there are: {', '.join(SAMPLES)} "
                          f"(`lfproc.sample_path() is their folder`)")
    return path
