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
