"""The README's microscope block, as written, on the real sea urchin (napari-LF's example: metadata.txt, its
radiometry frame as the white image, its dark frame, the light field), the command line and Python alike;
deconvolution at 2 iterations here (the settings are the README's otherwise: the full capture, ±40 µm)."""

from __future__ import annotations

import numpy as np

from conftest import ROOT
from readme_walk import own_data_section, run_commands, run_python, same_volume, volume_written


def test_the_readme_microscope_block_on_the_real_sea_urchin(real_dir, tmp_path):
    urchin = real_dir / "lfm-seaurchin"
    scope = tmp_path / "scope"
    scope.mkdir()
    for ours, theirs in (("metadata.txt", "metadata.txt"), ("white.tif", "radiometry_frame.tif"),
                         ("dark.tif", "dark_frame.tif"), ("capture.tif", "light_field.tif")):
        (scope / ours).symlink_to(urchin / theirs)
    (tmp_path / "samples").symlink_to(ROOT / "samples")
    section = own_data_section("A light-field microscope")
    procs = run_commands(section, tmp_path, extra={"deconvolve": ["--iterations", "2"]})
    assert not any("scene" in proc.stderr for proc in procs)              # no false alarm on its white image
    by_command = volume_written(scope / "volume")                        # before Python writes over it
    namespace = run_python(section, tmp_path, replace={"lfproc.deconvolve(lf, ": "lfproc.deconvolve(lf, iterations=2, "})
    stack, volume = namespace["z_stack"], namespace["volume"]
    assert stack.images.shape[0] == 9 and np.isfinite(stack.images).all()
    assert volume.data.max() > 0
    same_volume(volume, by_command)                                       # the command's volume, from Python
