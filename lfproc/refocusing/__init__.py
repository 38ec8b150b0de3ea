"""Shift-and-sum refocusing (the paper's Eq. 9, centred), with numba kernels that read the views once.

Semantics (the interface contract, ARCHITECTURE.md): for a light field ``views[ky, kx, jy, jx, ch]`` with m̂ × m̂
views and central index c = (m̂ − 1)/2, the slice of parameter ``a`` is ::

    out[jy, jx] = mean over (ky, kx) of views[ky, kx, jy + a·(c − ky), jx + a·(c − kx)]

which is Eq. 9 shifted by a constant a·c lenses so that the central view stays put and every slice
overlays the others. Conventions chosen here, all exact and tested:

Sample positions
    With ``upsample = s`` the output has ``((Ny − 1)·s + 1, (Nx − 1)·s + 1)`` pixels and output pixel
    (py, px) sits at lens position (py/s, px/s); view (ky, kx) is read at
    ``(py/s + a·(c − ky), px/s + a·(c − kx))``. ``s = 1`` is the plain formula above. A position within
    1e-9 lens of an integer is taken as that integer (so ``a = 1.1`` with a 10-view offset is a shift of
    exactly 11 lenses, not of 11.000000000000002).
Inside
    A sample counts when its position lies in ``[0, N − 1]`` on both axes; the mean divides by the
    number of samples that count, per output pixel. The rule is separable, so the count is
    ``count_y[py] · count_x[px]``. The central view always counts, so no pixel is ever empty.
Interpolation (for positions between lenses; whole-lens positions read the lens itself)
    ``"nearest"``: the lens at ``floor(pos + 0.5)`` (halves round up). ``"linear"``: bilinear, two taps
    per axis. ``"cubic"``: separable cubic convolution of Keys with a = −0.5 — the Catmull-Rom spline —
    four taps per axis at ``floor(pos) − 1 … floor(pos) + 2``; taps beyond the array are clamped to its
    edge. ``"cubic-sharp"``: the same with Keys' a = −0.9, which lifts the response between lenses.
    ``"cubic-spline"`` (the commands' default): the interpolating cubic spline through each view — the
    cubic B-spline's four taps on the views, then the recursive inverse filter (``_spline``) once on each
    summed slice, exact away from the border band (the filter commutes with the taps and the mean); a
    slice whose samples are all whole lenses is a gather. With linear (and, less, Catmull-Rom)
    interpolation an interpolated slice is blurrier than a whole-lens one, so the sharpest slice of a fine
    sweep snaps towards integer ``a``; the spline's response stays flat to a quarter cycle per lens, where
    :func:`slice_sharpness` measures, and holds it at the true ``a`` (docs/microscope-imaging.md).
    Whole-lens samples — every
    sample when ``a`` is an integer and ``upsample = 1`` — are a pure gather: no weights, no multiplications, whatever ``interpolation`` says (nearest with ``upsample = 1``
    is a gather too). A call whose slices are all gathers runs the gather kernel; integer slices that
    share a call with real ones take single unit-weight taps there, still without multiplications.
Precision
    Views are read in their own dtype (float32, float64 and uint16 without any copy; 8-bit integers,
    float16 and bool are converted to float32 first, other integers and floats wider than 64 bits
    (longdouble) to float64). The m̂ views of one
    view row are summed into a float32 row (float64 for float64 views) — exact for gathers of uint16
    data, whose sums of up to 256 views stay below 2**24 — and the view rows into float64 accumulators,
    so uint16 data near 65535 never overflows and hundreds of views lose nothing. The result is float32.
Non-finite input
    Finite float32 views so large (near 3.4e38) that their float32 row sums overflow are summed again
    in float64. Otherwise non-finite input is not scanned up front (that would cost a full extra pass
    over the data). NaN or ±inf pixels that reach a slice make that slice non-finite, which is detected on the (m̂² times smaller) output and
    raised as :class:`~lfproc.errors.LfprocError`; non-finite pixels that no sample reads are harmless.
    Finite float64 (or wider) views beyond the float32 range give a non-finite float32 result: that is
    reported as such (rescale the views), not as NaN input.

Performance: one call makes one pass over the views for all requested slices. Output rows are split
into bands; each band is one call of a numba kernel (``cache=True``, ``nogil=True``) and the bands run
on a thread pool of ``NUMBA_NUM_THREADS`` threads (default: all CPUs). Python threads over GIL-free
kernels rather than ``prange``: the same speed, half the first-call compile time (about 10 s instead
of 20 s of CPU for the three dtypes), and no OpenMP threading layer (safe to call from several threads
at once and to fork after). Within a band, for each view row ky, each view of the row is streamed
through once, its rows added as contiguous shifted segments (the shift is constant along a row) into
per-view-row partial sums of every slice that reads them; these go into the float64 accumulators.
Slices of one call thus share each loaded row instead of re-reading it from memory.
Interpolation is separable: the x-resampled sum of a source row is formed once and serves every output
row whose y-taps read it. At ``upsample = 1`` (``_interpolated_rows_band``) each view is x-resampled for
each slice in one loop nest over all the rows the band reads (the per-row bookkeeping done once per view
and slice): on a light-field microscope's short rows (27 × 27 views of 73 × 73 lenses, 101 slices) that
takes a half (cubic) to a sixth (linear) of the CPU time of the per-row ring of ``_interpolated_band``,
which still serves upsampled slices (bit-identical results).

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._block import refocus_view_block, view_weight_inside
from ._coverage import MIN_REFOCUSED_AREA, full_view_fraction, refocused_fraction, usable_a_bound
from ._refocus import INTERPOLATIONS, MAX_OUTPUT_BYTES, refocus
from ._sharpness import slice_sharpness
