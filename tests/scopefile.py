"""The text of a light-field microscope's camera file ([microscope] table, ARCHITECTURE.md), for the tests.

The defaults are the contract's example (a 20x/0.5 water-immersion objective, 125 µm f/20 lenslets, 6.5 µm
camera pixels); ``relay`` and ``wavelength`` are written only when given. Values are written as given
(``str``), so a test can edit a line of the text by its exact spelling.
"""


def microscope_toml(*, name: str | None = "lfm-20x", pixel=0.0065, pitch=0.125, f_s=2.433, grid="rectangular",
                    magnification=20.0, na=0.5, n=1.33, f_tube=180.0, relay=None, wavelength=None) -> str:
    lines = [f'name = "{name}"'] if name is not None else []
    lines += ["[sensor]", f"pixel_pitch_mm = {pixel}", "[mla]", f"pitch_mm = {pitch}", f"focal_length_mm = {f_s}"]
    lines += [f'grid = "{grid}"'] if grid is not None else []
    lines += ["[microscope]", f"objective_magnification = {magnification}", f"numerical_aperture = {na}",
              f"immersion_index = {n}", f"tube_lens_focal_length_mm = {f_tube}"]
    lines += [f"relay_magnification = {relay}"] if relay is not None else []
    lines += [f"wavelength_nm = {wavelength}"] if wavelength is not None else []
    return "\n".join(lines) + "\n"


#: the camera of `write_tiny_lfm`'s render: 47.5 µm lenslets on 6.5 µm pixels (7.3 px), the contract's 20x/0.5
TINY_LFM = microscope_toml(name="tiny-lfm", pitch=0.0475, f_s=0.95, grid=None, wavelength=510)


def write_tiny_lfm(folder):
    """A tiny light-field microscope's ``white.tif``, ``capture.tif`` (a smooth texture over the white image,
    16-bit) and ``lfm.toml`` (`TINY_LFM`) in ``folder``; returns ``folder``."""
    import numpy as np
    import tifffile

    from whitegen import covering_grid, white_image

    shape = (120, 128)
    grid = covering_grid(shape, "rectangular", 0.0475 / 0.0065, 0.3, (0.4, -0.2))
    white = np.asarray(white_image(shape, grid, 3.3), dtype=np.float64)
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    capture = white * (0.55 + 0.4 * np.sin(xx / 6.0) * np.cos(yy / 9.0))
    for name, image in (("white.tif", white), ("capture.tif", capture)):
        tifffile.imwrite(folder / name, np.round(image / image.max() * 60000).astype(np.uint16))
    (folder / "lfm.toml").write_text(TINY_LFM)
    return folder
