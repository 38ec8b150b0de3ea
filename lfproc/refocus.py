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
    edge. Whole-lens samples — every sample when ``a`` is an integer and ``upsample = 1`` — are a pure
    gather: no weights, no multiplications, whatever ``interpolation`` says (nearest with ``upsample = 1``
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
row whose y-taps read it.
"""

from __future__ import annotations

import math
import numbers
import sys
import types
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from .errors import LfprocError

INTERPOLATIONS = ("nearest", "linear", "cubic")

#: positions closer than this (in lenses) to an integer are snapped to it
SNAP_TOLERANCE = 1e-9

#: dtypes the kernels read directly; other real dtypes are converted (see the module docstring)
NATIVE_DTYPES = (np.dtype(np.float32), np.dtype(np.float64), np.dtype(np.uint16))

#: target size in bytes of one band's float64 accumulators (all slices of the call; the gather's
#: float32 partial sums add half as much again): L2/L3-resident
ACCUMULATOR_BUDGET_BYTES = 4 << 20

#: the largest output (K·Ny'·Nx'·C float32 values) one call may produce, in bytes; an ``upsample`` that
#: needs more raises LfprocError instead of running out of memory
MAX_OUTPUT_BYTES = 16 << 30

#: lower bound on band height, so that many slices in one call do not shrink bands to a few rows
#: (each band also reads the rows its slices' shifts add on top: the shorter the band, the more)
MIN_BAND_ROWS = 8


# ----------------------------------------------------------------------------- public entry point
def refocus(lf, a, interpolation: str = "linear", upsample: int = 1) -> np.ndarray:
    """Refocused slice(s) of a light field by centred shift-and-sum (Eq. 9).

    Parameters
    ----------
    lf : LightField or ndarray
        A :class:`~lfproc.lightfield.LightField`, or an array shaped ``(m̂, m̂, Ny, Nx, C)`` with m̂ odd
        (float32, float64, unsigned or signed integers; see the module docstring for precision).
    a : float or sequence of float
        Refocus parameter(s): the shift in lenses per view step (Eq. 9). Any finite real; positive a
        focuses nearer than a = 0. A sequence is rendered in one pass over the data.
    interpolation : {"nearest", "linear", "cubic"}
        How positions between lenses are read (module docstring). Irrelevant for integer ``a`` with
        ``upsample = 1``, which is a pure gather.
    upsample : int, optional
        Output grid ``s`` times finer: shape ``((Ny − 1)·s + 1, (Nx − 1)·s + 1)``, pixel (py, px) at lens
        position (py/s, px/s). ``1`` (default) is the lens grid itself. The output of the call (all K
        slices) may take at most :data:`MAX_OUTPUT_BYTES` (16 GiB).

    Returns
    -------
    ndarray, float32
        ``(Ny', Nx', C)`` for a scalar ``a``, ``(K, Ny', Nx', C)`` for a sequence of K values.

    Raises
    ------
    LfprocError
        Empty or non-finite ``a``, unknown ``interpolation``, bad ``upsample`` (or an output above
        :data:`MAX_OUTPUT_BYTES`), a malformed light field, non-finite pixels that reach a slice, or
        finite float64 values beyond the float32 range.
    """
    views = _views_array(lf)
    slopes, scalar = _slopes(a)
    interpolation = _interpolation(interpolation)
    upsample = _upsample(upsample)
    m, _, ny, nx, channels = views.shape
    _check_output_size(len(slopes), ny, nx, channels, upsample)
    plan_y = axis_plan(slopes, m, ny, upsample, interpolation)
    plan_x = axis_plan(slopes, m, nx, upsample, interpolation)
    out = _render(views, plan_y, plan_x, upsample)
    bad = ~np.isfinite(out).reshape(len(slopes), -1).all(axis=1)
    if bad.any() and views.dtype == np.float32 and np.isfinite(views).all():
        # finite float32 values near 3.4e38 overflow the float32 row sums: render again in float64
        # (only on this failure path, so the usual call pays nothing)
        out = _render(views.astype(np.float64), plan_y, plan_x, upsample)
        bad = ~np.isfinite(out).reshape(len(slopes), -1).all(axis=1)
    if bad.any():
        first_bad = slopes[int(np.argmax(bad))]
        if views.dtype == np.float64 and np.isfinite(views).all():
            raise LfprocError(f"light field values exceed the float32 range; rescale them (largest magnitude "
                              f"{float(np.abs(views).max()):.3g}, e.g. divide by it) before refocusing "
                              f"(slice a={first_bad:g})")
        raise LfprocError(f"light field has NaN or infinite pixels that reach the slice a={first_bad:g}; "
                          "replace them (e.g. numpy.nan_to_num) before refocusing")
    out = out.reshape(len(slopes), plan_y.count.shape[1], plan_x.count.shape[1], channels)
    return out[0] if scalar else out


# ----------------------------------------------------------------------------- input validation
def _views_array(lf) -> np.ndarray:
    """The ``(m̂, m̂, Ny, Nx, C)`` array of ``lf``, C-contiguous, in a dtype the kernels read."""
    views = getattr(lf, "views", lf)
    try:
        views = np.asarray(views)
    except Exception:  # pragma: no cover - exotic array-likes
        raise LfprocError("refocus needs a LightField or an array shaped (m, m, Ny, Nx, C)") from None
    if views.ndim != 5 or views.shape[0] != views.shape[1] or views.shape[0] % 2 == 0 or min(views.shape) < 1:
        raise LfprocError(f"refocus needs views shaped (m, m, Ny, Nx, C) with m odd and no empty axis, "
                          f"got shape {views.shape}; pass a LightField or reshape the array")
    kind = views.dtype.kind
    if views.dtype in NATIVE_DTYPES:
        pass
    elif kind in "iu":
        views = views.astype(np.float32 if views.dtype.itemsize == 1 else np.float64)
    elif kind == "f" and views.dtype.itemsize > 8:
        views = views.astype(np.float64)      # longdouble: keep the precision float64 can hold
    elif kind in "fb":
        views = views.astype(np.float32)
    else:
        raise LfprocError(f"refocus needs real-valued views, got dtype {views.dtype}; convert to float32")
    return np.ascontiguousarray(views)


def _check_output_size(n_slices: int, ny: int, nx: int, channels: int, upsample: int) -> None:
    """Refuse outputs above :data:`MAX_OUTPUT_BYTES` before allocating anything."""
    size = n_slices * ((ny - 1) * upsample + 1) * ((nx - 1) * upsample + 1) * channels * 4
    if size > MAX_OUTPUT_BYTES:
        raise LfprocError(f"refocus: upsample={upsample} with {n_slices} slice(s) would produce "
                          f"{size / 2**30:.1f} GiB of output (limit {MAX_OUTPUT_BYTES / 2**30:g} GiB); "
                          "use a smaller upsample or fewer a values per call")


def _slopes(a) -> tuple[tuple[float, ...], bool]:
    """``a`` as a tuple of finite floats, and whether it was a scalar."""
    arr = np.asarray(a, dtype=object) if not isinstance(a, np.ndarray) else a
    if arr.ndim > 1:
        raise LfprocError(f"refocus: a must be a number or a flat list of numbers, got shape {arr.shape}")
    scalar = arr.ndim == 0
    items = [arr.item()] if scalar else list(np.ravel(arr))
    if not items:
        raise LfprocError("refocus: the list of a values is empty; give at least one number")
    values = []
    for item in items:
        if isinstance(item, (bool, np.bool_)) or not isinstance(item, (numbers.Real, np.integer, np.floating)):
            raise LfprocError(f"refocus: a={item!r} is not a number; give real numbers like 0, 1.5, -2")
        value = float(item)
        if not math.isfinite(value):
            raise LfprocError(f"refocus: a={value} is not finite; give finite numbers like 0, 1.5, -2")
        values.append(value)
    return tuple(values), scalar


def _interpolation(name) -> str:
    if name not in INTERPOLATIONS:
        raise LfprocError(f"refocus: unknown interpolation {name!r}; use one of {', '.join(INTERPOLATIONS)}")
    return name


def _upsample(s) -> int:
    if isinstance(s, (bool, np.bool_)) or not isinstance(s, (numbers.Integral, np.integer)) or s < 1:
        raise LfprocError(f"refocus: upsample must be an integer >= 1, got {s!r}")
    return int(s)


# ----------------------------------------------------------------------------- sampling plans (pure numpy)
def keys_cubic_weights(t: np.ndarray) -> np.ndarray:
    """Weights of the four taps ``floor(pos) − 1 … floor(pos) + 2`` for fraction ``t`` (Keys, a = −0.5).

    This is the Catmull-Rom spline; the weights sum to one and reproduce the sample at ``t = 0``.
    Returns an array shaped ``t.shape + (4,)``.
    """
    t = np.asarray(t, dtype=np.float64)
    return np.stack([((-0.5 * t + 1.0) * t - 0.5) * t,
                     (1.5 * t - 2.5) * t * t + 1.0,
                     ((-1.5 * t + 2.0) * t + 0.5) * t,
                     (0.5 * t - 0.5) * t * t], axis=-1)


def snap(x: np.ndarray) -> np.ndarray:
    """``x`` with values within :data:`SNAP_TOLERANCE` of an integer replaced by that integer."""
    x = np.asarray(x, dtype=np.float64)
    nearest = np.round(x)
    return np.where(np.abs(x - nearest) < SNAP_TOLERANCE, nearest, x)


@dataclass(frozen=True)
class AxisPlan:
    """Where the output samples along one axis read each view: the separable half of Eq. 9.

    Output index ``p = q·s + r`` (phase ``r`` of the upsampling ``s``) reads view index ``v`` of slice
    ``k`` at position ``q + offset[k, v, r]``; it counts when ``lo[k, v, r] ≤ q ≤ hi[k, v, r]``
    (``lo > hi``: never) and then takes the taps ``q + first + t`` (``t < ntaps``, clamped to the
    array) with ``weights[..., t]``.
    """

    offset: np.ndarray   # (K, m, s) float64, snapped r/s + a·(c − v)
    first: np.ndarray    # (K, m, s) int64
    ntaps: np.ndarray    # (K, m, s) int64: 1, 2 or 4
    weights: np.ndarray  # (K, m, s, 4) float64, unused taps 0
    lo: np.ndarray       # (K, m, s) int64
    hi: np.ndarray       # (K, m, s) int64
    count: np.ndarray    # (K, P) int64: number of views that count at each output index

    @property
    def whole_lens(self) -> bool:
        """True when every sample is a single unit-weight tap (a pure gather)."""
        return bool(np.all(self.ntaps == 1) and np.all(self.weights[..., 0] == 1.0))


def axis_plan(slopes, m: int, n: int, upsample: int, interpolation: str) -> AxisPlan:
    """Sampling plan of one axis of length ``n`` for slices ``slopes`` of an m̂ = ``m`` light field."""
    s = upsample
    c = (m - 1) // 2
    a = np.asarray(slopes, dtype=np.float64)[:, None, None]
    v = np.arange(m)[None, :, None]
    r = np.arange(s)[None, None, :]
    with np.errstate(invalid="ignore", over="ignore"):     # |a| near 1e308 gives ±inf: outside
        offset = snap(r / s + a * (c - v))
    q_len = np.where(r == 0, n, n - 1)                       # outputs per phase: P = (n − 1)·s + 1
    lo_f = np.maximum(0.0, np.ceil(-offset))
    hi_f = np.minimum(q_len - 1.0, np.floor(n - 1.0 - offset))
    lo = np.clip(lo_f, -1, n + 1).astype(np.int64)
    hi = np.clip(hi_f, -1, n + 1).astype(np.int64)
    valid = lo <= hi
    safe = np.where(valid, offset, 0.0)                      # keeps huge |a| away from int conversion
    weights = np.zeros(offset.shape + (4,))
    if interpolation == "nearest":
        first = np.floor(safe + 0.5)
        ntaps = np.ones(offset.shape, dtype=np.int64)
        weights[..., 0] = 1.0
    else:
        base = np.floor(safe)
        frac = safe - base
        whole = frac == 0.0
        if interpolation == "linear":
            first = base
            ntaps = np.where(whole, 1, 2).astype(np.int64)
            weights[..., 0] = 1.0 - frac
            weights[..., 1] = frac
        else:
            first = np.where(whole, base, base - 1.0)
            ntaps = np.where(whole, 1, 4).astype(np.int64)
            weights[...] = np.where(whole[..., None], np.array([1.0, 0.0, 0.0, 0.0]), keys_cubic_weights(frac))
    p = np.arange((n - 1) * s + 1)
    q_of_p, r_of_p = p // s, p % s
    inside = (lo[:, :, r_of_p] <= q_of_p) & (q_of_p <= hi[:, :, r_of_p])   # (K, m, P)
    c_order = np.ascontiguousarray     # one memory layout, so the kernels compile once per dtype
    return AxisPlan(offset=c_order(offset), first=c_order(first, dtype=np.int64), ntaps=c_order(ntaps),
                    weights=c_order(weights), lo=c_order(lo), hi=c_order(hi),
                    count=c_order(inside.sum(axis=1), dtype=np.int64))


# ----------------------------------------------------------------------------- driver
def _thread_count() -> int:
    """Worker threads: ``NUMBA_NUM_THREADS`` (default: the CPUs available)."""
    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def _bands(n_slices: int, n_rows: int, row_len: int, threads: int) -> list[tuple[int, int]]:
    """Output row ranges processed one per task: float64 accumulators of all slices near the budget,
    and a number of bands that is a multiple of the thread count (so the threads finish together)."""
    accumulator_bytes = n_slices * n_rows * row_len * 8
    n_bands = max(threads, -(-accumulator_bytes // ACCUMULATOR_BUDGET_BYTES))
    n_bands = min(n_bands, max(threads, n_rows // MIN_BAND_ROWS))   # many slices: keep bands tall
    n_bands = min(n_rows, -(-n_bands // threads) * threads)
    edges = [i * n_rows // n_bands for i in range(n_bands + 1)]          # sizes differ by at most one
    return list(zip(edges[:-1], edges[1:]))


def _phase0(arr: np.ndarray) -> np.ndarray:
    """The ``r = 0`` phase of a ``(K, m, s)`` plan array, as a C-ordered ``(K, m)`` array."""
    return np.ascontiguousarray(arr[:, :, 0])


def _render(views: np.ndarray, plan_y: AxisPlan, plan_x: AxisPlan, upsample: int) -> np.ndarray:
    """Run the kernel that fits the plans over all bands of output rows; returns ``(K, Ny', Nx'·C)`` float32.

    The band kernels release the GIL, so bands run in parallel on a thread pool; they write disjoint
    rows of ``out``.
    """
    m, _, ny, nx, channels = views.shape
    flat = views.reshape(m, m, ny, nx * channels)
    n_slices, out_rows = plan_y.count.shape
    out_cols = plan_x.count.shape[1]
    out = np.empty((n_slices, out_rows, out_cols * channels), dtype=np.float32)
    # per-view-row partial sums: float32 unless the views are float64 (module docstring, Precision)
    part = np.zeros(0, dtype=np.float64 if views.dtype == np.float64 else np.float32)
    if upsample == 1 and plan_y.whole_lens and plan_x.whole_lens:
        args = (flat, channels, _phase0(plan_y.first), _phase0(plan_y.lo), _phase0(plan_y.hi),
                _phase0(plan_x.first), _phase0(plan_x.lo), _phase0(plan_x.hi), plan_y.count, plan_x.count)
        kernel = _gather_band
    else:
        args = (flat, channels, upsample, plan_y.first, plan_y.ntaps, plan_y.weights, plan_y.lo, plan_y.hi,
                plan_x.first, plan_x.ntaps, plan_x.weights.astype(part.dtype), plan_x.lo, plan_x.hi,
                plan_y.count, plan_x.count)
        kernel = _interpolated_band
    threads = _thread_count()
    bands = _bands(n_slices, out_rows, out_cols * channels, threads)
    if threads == 1 or len(bands) == 1:
        for row0, row1 in bands:
            kernel(*args, row0, row1, part, out)
    else:
        with ThreadPoolExecutor(max_workers=min(threads, len(bands))) as pool:
            list(pool.map(lambda rows: kernel(*args, rows[0], rows[1], part, out), bands))
    return out


class _CallableModule(types.ModuleType):
    """``import lfproc.refocus`` binds the package attribute ``lfproc.refocus`` to this module (Python
    sets it after the import), shadowing the lazily exported function; calling the module calls
    :func:`refocus`, so ``lfproc.refocus(lf, a)`` works whatever was imported first."""

    def __call__(self, *args, **kwargs):
        return refocus(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule


# ----------------------------------------------------------------------------- numba kernels
# Compiled lazily on first call (no signatures given) and cached on disk (cache=True), once per input
# dtype; numba is imported with this module, which ``import lfproc`` does not import. ``views`` arrive
# as (m, m, Ny, Nx·C): each (ky, kx, row) is one contiguous segment of Nx·C values, and the shift of a
# view is constant along a row, so every inner loop runs over contiguous slices (slices, not offset
# indices, so that LLVM sees non-negative indices and vectorises).
# Per band of output rows and view row ky, the m̂ views of that view row are summed, shifted, into
# per-view-row partial sums, which then go into the float64 accumulators of the slices (the band is
# sized to keep both in L2/L3). A source row is fetched from memory once per band and used by every
# slice that reads it; neighbouring bands re-read only the rows that their slices' shifts share.

@numba.njit(cache=True, nogil=True)
def _normalise(acc, count_y, count_x, channels, row0, out):
    """``out[k, row0 + i] = acc[k, i] / (count_y · count_x)``: the mean of Eq. 9 over the samples inside."""
    n_slices, n_rows, row_len = acc.shape
    cols = row_len // channels
    for k in range(n_slices):
        for i in range(n_rows):
            cy = count_y[k, row0 + i]
            for jx in range(cols):
                scale = 1.0 / (cy * count_x[k, jx])
                for ch in range(channels):
                    e = jx * channels + ch
                    out[k, row0 + i, e] = acc[k, i, e] * scale


@numba.njit(cache=True, nogil=True)
def _add_into(acc_row, part):
    for i in range(acc_row.shape[0]):
        acc_row[i] += part[i]


@numba.njit(cache=True, nogil=True)
def _gather_band(views, channels, first_y, lo_y, hi_y, first_x, lo_x, hi_x, count_y, count_x,
                 row0, row1, part_kind, out):
    """Output rows ``row0 … row1 − 1`` of every slice for whole-lens shifts (integer ``a``, or nearest, at
    ``upsample = 1``): pure adds of shifted row segments, no weights.

    ``first_*[k, v]`` is the shift of view index v for slice k; ``lo_*``/``hi_*`` the output range that
    reads inside the view. Loop order: view row ky, view column kx, source row sy, slice k — each view
    is read as one contiguous stream of the band's rows (what hardware prefetchers do best), each row
    once for all the slices that use it, into per-view-row partial sums ``part`` that then go into the
    float64 accumulators.
    """
    m = views.shape[0]
    src_rows = views.shape[2]
    n_slices, _, row_len = out.shape
    acc = np.zeros((n_slices, row1 - row0, row_len))
    part = np.empty((n_slices, row1 - row0, row_len), dtype=part_kind.dtype)
    for ky in range(m):
        # the source rows that any slice reads for this band and view row
        sy_lo = src_rows
        sy_hi = -1
        for k in range(n_slices):
            j0 = max(row0, lo_y[k, ky])
            j1 = min(row1 - 1, hi_y[k, ky])
            if j0 <= j1:
                sy_lo = min(sy_lo, j0 + first_y[k, ky])
                sy_hi = max(sy_hi, j1 + first_y[k, ky])
        part[:] = 0
        for kx in range(m):
            for sy in range(sy_lo, sy_hi + 1):
                for k in range(n_slices):
                    jy = sy - first_y[k, ky]
                    if jy < row0 or jy >= row1 or jy < lo_y[k, ky] or jy > hi_y[k, ky]:
                        continue
                    if lo_x[k, kx] > hi_x[k, kx]:
                        continue
                    e0 = lo_x[k, kx] * channels
                    e1 = (hi_x[k, kx] + 1) * channels
                    off = first_x[k, kx] * channels
                    dst = part[k, jy - row0, e0:e1]
                    src = views[ky, kx, sy, e0 + off:e1 + off]
                    for i in range(dst.shape[0]):
                        dst[i] += src[i]
        for k in range(n_slices):
            for jy in range(max(row0, lo_y[k, ky]), min(row1 - 1, hi_y[k, ky]) + 1):
                _add_into(acc[k, jy - row0], part[k, jy - row0])
    _normalise(acc, count_y, count_x, channels, row0, out)


@numba.njit(cache=True, nogil=True)
def _add_taps_clamped(dst, src, channels, s, r, n, first, ntaps, w, q_from, q_to):
    """Outputs ``q_from … q_to`` of phase r, taps with source indices clamped to ``[0, n − 1]`` (cubic edges)."""
    for q in range(q_from, q_to + 1):
        o = (q * s + r) * channels
        for t in range(ntaps):
            i = min(max(q + first + t, 0), n - 1) * channels
            for ch in range(channels):
                dst[o + ch] += w[t] * src[i + ch]


@numba.njit(cache=True, nogil=True)
def _add_taps_strided(dst, src, channels, s, r, first, ntaps, w, q_from, q_to):
    """Outputs ``q_from … q_to`` of phase r of an upsampled row (stride ``s`` pixels), all taps inside."""
    for q in range(q_from, q_to + 1):
        o = (q * s + r) * channels
        i = (q + first) * channels
        for ch in range(channels):
            value = w[0] * src[i + ch]
            for t in range(1, ntaps):
                value += w[t] * src[i + t * channels + ch]
            dst[o + ch] += value


@numba.njit(cache=True, nogil=True)
def _add_row(dst, src, channels, s, n, first, ntaps, w, lo, hi):
    """Add one source row of one view, resampled along x at every phase r of the output grid, to ``dst``.

    ``first``, ``ntaps``, ``lo``, ``hi`` (per phase) and ``w`` (phase × tap) are that view's x plan.
    """
    for r in range(s):
        q0 = lo[r]
        q1 = hi[r]
        if q0 > q1:
            continue
        f = first[r]
        nt = ntaps[r]
        # outputs whose taps q + f … q + f + nt − 1 all lie inside [0, n − 1]; only cubic has others
        qa = max(q0, -f)
        qb = min(q1, n - nt - f)
        if qa > qb:
            _add_taps_clamped(dst, src, channels, s, r, n, f, nt, w[r], q0, q1)
            continue
        _add_taps_clamped(dst, src, channels, s, r, n, f, nt, w[r], q0, qa - 1)
        _add_taps_clamped(dst, src, channels, s, r, n, f, nt, w[r], qb + 1, q1)
        if s != 1:
            _add_taps_strided(dst, src, channels, s, r, f, nt, w[r], qa, qb)
            continue
        e0 = qa * channels
        e1 = (qb + 1) * channels
        off = f * channels
        d = dst[e0:e1]
        s0 = src[e0 + off:e1 + off]
        w0 = w[r, 0]
        if nt == 1:
            if w0 == 1.0:
                for i in range(d.shape[0]):
                    d[i] += s0[i]
            else:
                for i in range(d.shape[0]):
                    d[i] += w0 * s0[i]
        elif nt == 2:
            s1 = src[e0 + off + channels:e1 + off + channels]
            w1 = w[r, 1]
            for i in range(d.shape[0]):
                d[i] += w0 * s0[i] + w1 * s1[i]
        else:
            s1 = src[e0 + off + channels:e1 + off + channels]
            s2 = src[e0 + off + 2 * channels:e1 + off + 2 * channels]
            s3 = src[e0 + off + 3 * channels:e1 + off + 3 * channels]
            w1 = w[r, 1]
            w2 = w[r, 2]
            w3 = w[r, 3]
            for i in range(d.shape[0]):
                d[i] += w0 * s0[i] + w1 * s1[i] + w2 * s2[i] + w3 * s3[i]


@numba.njit(cache=True, nogil=True)
def _interpolated_band(views, channels, s, first_y, ntaps_y, w_y, lo_y, hi_y,
                       first_x, ntaps_x, w_x, lo_x, hi_x, count_y, count_x, row0, row1, part_kind, out):
    """Output rows ``row0 … row1 − 1`` of every slice in the general case: fractional positions and/or
    upsampling, separable taps (see :class:`AxisPlan`).

    Separable: for a view row ky and slice k every view of the row reads the same source row, so the
    x-resampled sum over kx of source row sy is formed once and kept in a ring of four rows (the rows an
    output row needs are at most four consecutive ones, and they only move forward with the output
    row); each output row then adds its y-taps' weighted rows from the ring.
    """
    m = views.shape[0]
    src_rows = views.shape[2]
    src_cols = views.shape[3] // channels
    n_slices, _, row_len = out.shape
    acc = np.zeros((n_slices, row1 - row0, row_len))
    ring = np.empty((n_slices, 4, row_len), dtype=part_kind.dtype)
    ring_row = np.empty((n_slices, 4), dtype=np.int64)
    for ky in range(m):
        ring_row[:] = -1
        for py in range(row0, row1):
            q = py // s
            r = py - q * s
            for k in range(n_slices):
                if q < lo_y[k, ky, r] or q > hi_y[k, ky, r]:
                    continue
                dst = acc[k, py - row0]
                for t in range(ntaps_y[k, ky, r]):
                    sy = min(max(q + first_y[k, ky, r] + t, 0), src_rows - 1)
                    slot = sy % 4
                    x_sum = ring[k, slot]
                    if ring_row[k, slot] != sy:
                        x_sum[:] = 0
                        for kx in range(m):
                            _add_row(x_sum, views[ky, kx, sy], channels, s, src_cols,
                                     first_x[k, kx], ntaps_x[k, kx], w_x[k, kx], lo_x[k, kx], hi_x[k, kx])
                        ring_row[k, slot] = sy
                    wy = w_y[k, ky, r, t]
                    if wy == 1.0:
                        _add_into(dst, x_sum)
                    else:
                        for i in range(row_len):
                            dst[i] += wy * x_sum[i]
    _normalise(acc, count_y, count_x, channels, row0, out)
