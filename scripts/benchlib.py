"""Helpers of ``scripts/bench.py``: timing, peak memory, fits, references, tables and the plot.

Small pure functions; nothing here knows about the pipeline's stages. Kept out of ``lfproc`` because
only the benchmark needs them.
"""

from __future__ import annotations

import datetime as _dt
import gc
import math
import os
import platform
import statistics
import time
import tracemalloc
from dataclasses import asdict, dataclass, field

import numpy as np


# ----------------------------------------------------------------------------- timing and memory
@dataclass(frozen=True)
class Timing:
    """Wall times of one measured operation.

    Attributes
    ----------
    median_s, min_s : float
        Median and minimum of the timed runs (the warm-up is not among them).
    runs_s : list of float
        Every timed run, in order.
    cpu_median_s : float or None
        Median CPU time (user + system, every thread of the process) of the timed runs: steadier than the
        wall time on a shared machine, and above it where the work runs on several cores.
    peak_mb : float or None
        tracemalloc peak of the warm-up call, above the memory traced before it, in MB (1e6 bytes):
        numpy allocations (OpenCV's outputs are numpy arrays too), not numba's internal buffers.
    """

    median_s: float
    min_s: float
    runs_s: list = field(default_factory=list)
    peak_mb: float | None = None
    cpu_median_s: float | None = None

    def as_dict(self) -> dict:
        return asdict(self)


def traced_peak_mb(fn) -> tuple[object, float]:
    """Call ``fn()`` under tracemalloc: its result and the peak of newly traced memory in MB."""
    gc.collect()
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        result = fn()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return result, max(0.0, (peak - base) / 1e6)


def measure(fn, repeats: int, *, memory: bool = True) -> Timing:
    """Median of ``repeats`` timed calls of ``fn()`` after one untimed warm-up call.

    With ``memory`` the warm-up runs under tracemalloc and gives the peak memory.
    """
    return measure_keeping(fn, repeats, memory=memory)[0]


def measure_keeping(fn, repeats: int, *, memory: bool = True) -> tuple[Timing, object]:
    """:func:`measure`, also returning the result of the last timed call."""
    peak = None
    if memory:
        _, peak = traced_peak_mb(fn)
    else:
        fn()
    runs, cpu, result = [], [], None
    for _ in range(max(1, repeats)):
        result = None          # the previous result's memory is free before the next run
        gc.collect()
        start, start_cpu = time.perf_counter(), time.process_time()
        result = fn()
        runs.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return Timing(statistics.median(runs), min(runs), runs, peak, statistics.median(cpu)), result


def time_once(fn) -> tuple[object, float]:
    """``(fn(), seconds)`` for one call."""
    start = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - start


# ----------------------------------------------------------------------------- fits and metrics
def power_law_fit(x, y) -> dict:
    """Least-squares fit of ``y = k·x**p`` in log-log space: ``{"exponent", "prefactor", "r2"}``."""
    lx, ly = np.log(np.asarray(x, dtype=np.float64)), np.log(np.asarray(y, dtype=np.float64))
    if lx.size < 2 or np.ptp(lx) == 0:
        raise ValueError("a power-law fit needs at least two distinct x values")
    slope, intercept = np.polyfit(lx, ly, 1)
    residual = ly - (slope * lx + intercept)
    total = np.sum((ly - ly.mean()) ** 2)
    r2 = 1.0 - float(np.sum(residual ** 2) / total) if total > 0 else 1.0
    return {"exponent": float(slope), "prefactor": float(math.exp(intercept)), "r2": r2}


def psnr_db(test: np.ndarray, reference: np.ndarray, peak: float | None = None) -> float:
    """Peak signal-to-noise ratio in dB; the peak defaults to the reference's maximum. ``inf`` if equal."""
    test = np.asarray(test, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    mse = float(np.mean((test - reference) ** 2))
    top = float(np.max(np.abs(reference))) if peak is None else float(peak)
    return math.inf if mse == 0 else 10.0 * math.log10(top * top / mse)


def views_inside_cell(m_hat: int, kind: str = "rectangular", rings_excluded: int = 1) -> np.ndarray:
    """``(m̂, m̂)`` booleans: views whose sample centre lies inside its lens's cell by a margin.

    View (ky, kx) is read at ((kx − c), (ky − c))/m̂ pitches from the lens centre along the lattice axes.
    The lens's cell (its share of the sensor) is the square of side 1 pitch for a rectangular lattice and
    the hexagon between the six neighbours for a hexagonal one: |offset · n| ≤ ½ for each neighbour
    direction n. A view is kept when |offset · n| ≤ ½ − (rings_excluded + ½)/m̂: for a rectangular lattice
    exactly the views inside the outer ``rings_excluded`` rings. Views beyond read the neighbouring micro
    image (crosstalk, see ``lfproc.decode``); on a hexagonal lattice that includes the corners of the square.
    """
    c = (m_hat - 1) // 2
    k = (np.arange(m_hat) - c) / m_hat
    ox, oy = k[None, :], k[:, None]
    if kind == "rectangular":
        directions = [(1.0, 0.0), (0.0, 1.0)]
    else:
        directions = [(1.0, 0.0), (0.5, math.sqrt(3.0) / 2.0), (-0.5, math.sqrt(3.0) / 2.0)]
    limit = 0.5 - (rings_excluded + 0.5) / m_hat + 1e-9
    keep = np.ones((m_hat, m_hat), dtype=bool)
    for nx, ny in directions:
        keep &= np.abs(ox * nx + oy * ny) <= limit
    return keep


def decode_psnr_mask(weight: np.ndarray, kind: str = "rectangular", rings_excluded: int = 1,
                     min_weight: float = 0.999) -> np.ndarray:
    """Samples compared with the ideal views: all rays pass, not on a border lens, view inside its cell.

    See :func:`views_inside_cell`; border lenses have incomplete neighbours for the interpolation.
    """
    mask = (weight > min_weight) & views_inside_cell(weight.shape[0], kind, rings_excluded)[:, :, None, None]
    mask[:, :, [0, -1], :] = False
    mask[:, :, :, [0, -1]] = False
    return mask


def nearest_distance_rms(points_xy: np.ndarray, lattice_xy: np.ndarray) -> float:
    """RMS distance from each point to its nearest lattice point (both ``(N, 2)``)."""
    from scipy.spatial import cKDTree

    dist, _ = cKDTree(lattice_xy).query(points_xy)
    return float(np.sqrt(np.mean(dist ** 2)))


# ----------------------------------------------------------------------------- float64 refocus reference
def _keys_kernel(x: np.ndarray, a: float = -0.5) -> np.ndarray:
    """Keys' cubic convolution kernel W(x) (a = −0.5: Catmull-Rom), piecewise form."""
    x = np.abs(x)
    inner = ((a + 2.0) * x - (a + 3.0)) * x * x + 1.0
    outer = ((a * x - 5.0 * a) * x + 8.0 * a) * x - 4.0 * a
    return np.where(x <= 1.0, inner, np.where(x < 2.0, outer, 0.0))


def interpolation_matrix(positions: np.ndarray, n: int, interpolation: str) -> np.ndarray:
    """Dense ``(len(positions), n)`` matrix whose rows interpolate a length-``n`` signal at ``positions``.

    Taps outside ``[0, n − 1]`` are clamped to the edge sample. Positions within 1e-9 of an integer
    are that integer.
    """
    pos = np.asarray(positions, dtype=np.float64)
    rounded = np.round(pos)
    pos = np.where(np.abs(pos - rounded) < 1e-9, rounded, pos)
    matrix = np.zeros((pos.size, n))
    rows = np.arange(pos.size)
    if interpolation == "nearest":
        np.add.at(matrix, (rows, np.clip(np.floor(pos + 0.5), 0, n - 1).astype(int)), 1.0)
        return matrix
    base = np.floor(pos)
    taps = range(0, 2) if interpolation == "linear" else range(-1, 3)
    for t in taps:
        tap = base + t
        if interpolation == "linear":
            weight = np.maximum(0.0, 1.0 - np.abs(pos - tap))
        elif interpolation == "cubic":
            weight = _keys_kernel(pos - tap)
        else:
            raise ValueError(f"unknown interpolation {interpolation!r}")
        np.add.at(matrix, (rows, np.clip(tap, 0, n - 1).astype(int)), weight)
    return matrix


def refocus_reference(views: np.ndarray, a: float, interpolation: str = "linear", upsample: int = 1) -> np.ndarray:
    """Plain float64 numpy implementation of the contract's refocus formula (ARCHITECTURE.md, Eq. 9 centred).

    ``out[p] = mean over views (ky, kx) whose sample position lies in [0, N − 1] on both axes of
    views[ky, kx] interpolated at (py/s + a·(c − ky), px/s + a·(c − kx))``, output ``(Ny − 1)·s + 1`` by
    ``(Nx − 1)·s + 1`` pixels. Separable interpolation by two dense matrices per view; slow, but exact.
    """
    v = np.asarray(views, dtype=np.float64)
    m, _, ny, nx, channels = v.shape
    c = (m - 1) // 2
    s = int(upsample)
    grid_y = np.arange((ny - 1) * s + 1) / s
    grid_x = np.arange((nx - 1) * s + 1) / s
    acc = np.zeros((grid_y.size, grid_x.size, channels))
    count = np.zeros((grid_y.size, grid_x.size))
    for ky in range(m):
        pos_y = grid_y + a * (c - ky)
        in_y = (pos_y >= -1e-9) & (pos_y <= ny - 1 + 1e-9)
        w_y = interpolation_matrix(pos_y, ny, interpolation)
        for kx in range(m):
            pos_x = grid_x + a * (c - kx)
            in_x = (pos_x >= -1e-9) & (pos_x <= nx - 1 + 1e-9)
            w_x = interpolation_matrix(pos_x, nx, interpolation)
            sample = np.einsum("pi,ijc,qj->pqc", w_y, v[ky, kx], w_x, optimize=True)
            inside = in_y[:, None] & in_x[None, :]
            acc += np.where(inside[:, :, None], sample, 0.0)
            count += inside
    return acc / count[:, :, None]


def plane_light_field(m_hat: int, shape: tuple[int, int], disparity: float) -> tuple[np.ndarray, callable]:
    """Views of one fronto-parallel textured plane that refocus at ``a = disparity`` brings into focus.

    ``views[ky, kx, y, x] = f(y − d·(c − ky), x − d·(c − kx))`` with f a sum of two sinusoids below
    a quarter of the lens sampling rate, so ``refocus(views, d)`` should return ``f`` on the output grid;
    what it misses is the interpolation's error. Returns ``(views float32 (m̂, m̂, Ny, Nx, 1), f)``.
    """
    def texture(y, x):
        return (0.5 + 0.25 * np.cos(2 * np.pi * (0.11 * y + 0.07 * x) + 0.3)
                + 0.2 * np.cos(2 * np.pi * (-0.05 * y + 0.19 * x) + 1.1))

    c = (m_hat - 1) // 2
    k = np.arange(m_hat)
    y = np.arange(shape[0])[None, None, :, None] - disparity * (c - k)[:, None, None, None]
    x = np.arange(shape[1])[None, None, None, :] - disparity * (c - k)[None, :, None, None]
    views = texture(y, x).astype(np.float32)[..., None]
    return views, texture


# ----------------------------------------------------------------------------- machine description
def machine_info() -> dict:
    """CPU, thread settings, library versions, date and load: what a reader needs to compare runs."""
    import cv2
    import numba
    import scipy

    model = platform.processor() or ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        import OpenImageIO as oiio
        oiio_version = oiio.__version__
    except Exception:  # pragma: no cover - informational only
        oiio_version = "unavailable"
    memory_gb = None
    try:
        memory_gb = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9
    except (ValueError, OSError, AttributeError):
        pass
    return {
        "date": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
        "cpu_model": model,
        "cpu_count": os.cpu_count(),
        "cpus_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count(),
        "memory_gb": memory_gb,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "opencv": cv2.__version__,
        "openimageio": oiio_version,
        "scipy": scipy.__version__,
        "numba_threads": int(numba.config.NUMBA_NUM_THREADS),
        "opencv_threads": int(cv2.getNumThreads()),
        "load_average_start": list(os.getloadavg()),
    }


# ----------------------------------------------------------------------------- formatting
def fmt(value, digits: int = 3) -> str:
    """A number for a table: ``—`` for None, ``∞`` for inf, otherwise ``digits`` significant digits."""
    if value is None:
        return "—"
    if isinstance(value, str):
        return value
    value = float(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    if value == 0:
        return "0"
    magnitude = abs(value)
    if 10 ** digits <= magnitude < 1e6:
        return f"{value:.0f}"
    if magnitude >= 1e6 or magnitude < 1e-3:
        return f"{value:.{max(digits - 1, 0)}e}"
    decimals = max(0, digits - 1 - int(math.floor(math.log10(magnitude))))
    return f"{value:.{decimals}f}"


def fmt_timing(timing: dict) -> str:
    """A :class:`Timing` (as a dict) for a table: the median, the minimum in brackets."""
    return f"{fmt(timing['median_s'])} ({fmt(timing['min_s'])})"


def fmt_peak(timing: dict) -> str:
    """The traced peak memory of a :class:`Timing` (as a dict), in MB."""
    return fmt(timing.get("peak_mb"), 2 if (timing.get("peak_mb") or 0) < 10 else 3)


def markdown_table(headers: list[str], rows: list[list]) -> str:
    """A GitHub markdown table; cells are formatted with :func:`fmt` unless already strings."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join(" --- " for _ in headers) + "|"]
    for row in rows:
        lines.append("| " + " | ".join(fmt(cell) for cell in row) + " |")
    return "\n".join(lines)


# ----------------------------------------------------------------------------- plot
def plot_scaling(path: str, decode_sizes_mpx, decode_times_s, decode_fit: dict, slices, refocus_times_s,
                 refocus_fit: dict, *, calibrate_sizes_mpx=(), calibrate_times_s=(), refocus_floor_s=None,
                 refocus_real_times_s=None, refocus_real_fit: dict | None = None) -> None:
    """Two panels: stage time against sensor size (log-log), refocus time against slices per call.

    Written atomically (PNG, matplotlib's Agg backend).
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from lfproc.atomic import atomic_path

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.4), constrained_layout=True)
    sizes = np.asarray(decode_sizes_mpx, dtype=float)
    line = np.geomspace(sizes.min() / 1.3, sizes.max() * 1.3, 50)
    left.loglog(sizes, decode_times_s, "o", color="C0", label="decode (linear, fast demosaic)")
    left.loglog(line, decode_fit["prefactor"] * line ** decode_fit["exponent"], "-", color="C0", alpha=0.6,
                label=f"fit: t ∝ size^{decode_fit['exponent']:.2f}")
    if len(calibrate_sizes_mpx):
        left.loglog(calibrate_sizes_mpx, calibrate_times_s, "s", color="C1", label="calibrate (estimate_grid)")
    from matplotlib.ticker import FixedLocator, NullLocator
    left.xaxis.set_major_locator(FixedLocator(sizes))
    left.xaxis.set_minor_locator(NullLocator())
    left.set_xticklabels([f"{v:.3g}" for v in sizes])
    left.set_xlabel("sensor size [Mpx]")
    left.set_ylabel("time per call [s]")
    left.set_title("cost against sensor size")
    left.grid(True, which="both", alpha=0.3)
    left.legend(fontsize=8)

    k = np.asarray(slices, dtype=float)
    kk = np.linspace(k.min(), k.max(), 100)
    right.plot(k, refocus_times_s, "o", color="C2", label="integer a (gather)")
    right.plot(kk, refocus_fit["prefactor"] * kk ** refocus_fit["exponent"], "-", color="C2", alpha=0.6,
               label=f"fit: t ∝ K^{refocus_fit['exponent']:.2f}")
    if refocus_real_times_s is not None and refocus_real_fit is not None:
        right.plot(k, refocus_real_times_s, "^", color="C3", label="real a, linear")
        right.plot(kk, refocus_real_fit["prefactor"] * kk ** refocus_real_fit["exponent"], "-", color="C3",
                   alpha=0.6, label=f"fit: t ∝ K^{refocus_real_fit['exponent']:.2f}")
    if refocus_floor_s is not None:
        right.axhline(refocus_floor_s, color="grey", linestyle="--", label="floor: views.sum(axis=(0, 1))")
    right.set_xlabel("slices per refocus call K")
    right.set_ylabel("time per call [s]")
    right.set_title("refocus cost against slices (one pass over the views)")
    right.set_ylim(bottom=0)
    right.grid(True, alpha=0.3)
    right.legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
