"""Decoding: resample a sensor image along the fitted lens lattice into m̂ × m̂ views (paper Section 5.1).

Real captures rarely have an odd, integer number of pixels per micro lens, or a lattice aligned with
the pixel rows. The paper resamples the raw image so every micro image is m̂ × m̂ pixels with m̂ odd
(9 µm pixels under 250 µm lenses → m̂ = 25 at an effective pitch of 10 µm). Here that is ``cv2.remap``
over bands of lens rows:

* **Sample positions** (``_positions``). View (ky, kx) of lens (r, q) is read at the lens centre
  (``grid.lens_xy``) plus ``(kx − c)·s·u + (ky − c)·s·v`` sensor pixels, with s = pitch_px / m̂ the
  effective pixel and (u, v) the lattice axes. The maps are laid out as ``(ky, kx, r)`` rows by ``q``
  columns, so ``remap`` writes the contract's ``(m̂, m̂, Ny, Nx, C)`` array directly.
* **Read plan** (``_plan``, band reading ``_band``). A :class:`Decoder` reads lens rows in bands
  planned once (its ``read_plan``: grid, m̂, methods, sample shifts, cells, shares, rim-aware white,
  delivered runs, bands and their sensor strips); the output is bit-identical for any band size.
* **Devignetting** (``_inverse_white``). The white image is demosaiced and resampled the same way, and the
  decoded value is ``remap(capture) / remap(white)``: the scene radiance in units of the white image,
  white balance included for colour sensors. Samples where the white image is darker than
  ``dark_fraction`` of its bright level in any channel carry no signal and are set to 0 in every
  channel (never NaN, never one channel alone: that would colour them).
* **Own cells** (``_cells``): every lens is read from its own cell only (the pixels nearer to its
  centre than to any other), demosaicing included, so no sample mixes in the neighbouring micro image.
* **Delivered views** (``_view_mask``): exactly the views lit at their nominal position (inside the main
  lens aperture or the objective's NA, never the gaps between micro images), symmetric; an outer view
  whose samples' white-weighted centroid is off nominal is read further out, where its rays are — see
  *the refocus bias* below.
* **Whole lenses** (``_whole_lenses``): by default the grid is cropped to the lenses whose delivered
  samples all lie on the sensor, so no partial lens leaks black or extrapolated samples; the light
  field's grid is the cropped one, so lens indices stay those of refocusing and depth.
* **Demosaicing** (Bayer captures) of the sensor strip a band reads, before resampling. ``"fast"`` (the
  default) is *rim-aware* (``_rim_demosaic``, kernel ``_rim_kernel``): every pixel keeps its own
  devignetted value and takes the other channels from the hue of its micro image, so every channel of
  a sample stands for the pixel's own ray, up to the rim (bilinear red and blue there are read from
  further in); samples are read like a mono sensor's, weighted by the white, and pixels on a cell
  border count for both lenses by their distance from it (``_cells.cell_shares``). ``"careful"`` is
  OpenCV's edge-aware (EA) demosaicing of each class's cells (``_demosaic``), as before.
* **Interpolation** (``_resample``): ``"nearest"``, ``"linear"``, ``"cubic"``, ``"lanczos"``.
* **Hexagonal grids** (``_hexagonal``) are decoded at their own lens centres, then each view is
  resampled onto a rectangular lens grid of the same pitch (:func:`hex_to_rect`), band by band.

The refocus bias (issue 13) and its cause
    A refocus sweep over a decoded capture used to peak at a lower a than the truth (1.78 for a true
    1.93 on an RGGB render of 12 px lenses at m̂ = 11; 3 % too far). Per-view parallax measurements
    against the simulator's ideal views located it: the inner views were right, the outer ones had
    compressed parallax (a ≈ 1.82 for |k − c| = 5). A decoded sample is ``K·capture / K·white`` for its
    kernel K (sensor pixel ⊗ demosaicing ⊗ interpolation, ±2.5 px for bilinear Bayer + linear remap).
    Where K reaches past the edge of the lens's own lit micro image, the dark part weighs nothing after
    the division, so the sample's white-weighted centroid — the ray direction it really stands for —
    moves inwards, and lit pixels of the neighbouring micro image enter as crosstalk. The sample
    positions, the effective pitch (pitch/m̂ in both the decoder and ``geometry``) and the truth were
    right. The decoder measures that centroid from the white image itself (``_view_mask``): views right
    at nominal are read there, the others are read up to 0.75 effective pixel further out, where the
    mean centroid is nominal (a rim pixel counting at the centre of its lit part), and delivered if that
    works; a sweep then peaks within 0.006 of the true a (``tests/test_decode_bias.py``) with 89 of the
    97 views inside the aperture (mono, hexagonal RGGB) and 77 (rectangular RGGB) instead of 45–69.
    Two measurement traps found on the way: linearly interpolated refocusing peaks towards integer a
    (1.93 → 2.00 on exactly shifted synthetic views), and the simulator's ideal views that the stop
    cuts partly (weight < 1) have the same inward centroid (ideal views with them: 1.896).

Crosstalk. With micro images that fill their cells, the outer ring of views would read the
neighbouring micro image; reading every lens from its own cell keeps it out.

The white image's views depend only on the white image, the grid and the settings, so a
:class:`Decoder` computes them once and then decodes any number of captures.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._decoder import Decoder, decode, decode_capture, make_decoder
from ._plan import Band
from ._demosaic import demosaic, to_channels
from ._hexagonal import hex_to_rect, rect_row_count
from ._positions import remap_maps, sample_positions
from ._resample import INTERPOLATIONS, resample_views
from ._view_mask import view_sampling
