"""How many worker processes fit this machine."""

from __future__ import annotations

import contextlib
import os


def available_memory_bytes() -> float:
    """Memory available to new processes: Linux's MemAvailable, else free pages, else 8 GB."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover
        return 8e9


def default_workers(sample_path: str | None, memory_fraction: float = 0.5, extra_bytes: float = 0.0) -> int:
    """Processes that fit: at most the cores, and at most ``memory_fraction`` of the available memory.

    A worker process peaks at about :data:`PROCESS_BASE_BYTES` plus :data:`BYTES_PER_SENSOR_PIXEL` bytes
    per sensor pixel (the white image read, demosaiced and calibrated in float32, its decoded views,
    then each capture's sensor image, views and refocused stack). The pixel count comes from the first
    capture's header when OpenImageIO can read it, else a 40-megapixel sensor is assumed. ``extra_bytes``:
    what else each process holds (a deconvolution's operators and projection matrices).
    """
    cores = os.cpu_count() or 1
    pixels = 40e6
    if sample_path is not None:
        with contextlib.suppress(Exception):  # the estimate only sizes the pool
            import OpenImageIO as oiio

            from ..io import libraries_quiet

            with libraries_quiet():      # a damaged file is reported by the capture's own reading, once
                inp = oiio.ImageInput.open(sample_path)
            if inp:
                spec = inp.spec()
                pixels = float(spec.width * spec.height)
                inp.close()
            else:   # retrieve the error: OpenImageIO prints a pending one when the process exits
                oiio.geterror()
    per_process = PROCESS_BASE_BYTES + pixels * BYTES_PER_SENSOR_PIXEL + extra_bytes
    return max(1, min(cores, int(memory_fraction * available_memory_bytes() // per_process)))


#: peak bytes per sensor pixel of a worker process (see default_workers). Measured peak resident memory of
#: one worker, reached while calibrating the white image: 290 MB at 0.5 megapixels (the bundled sample),
#: 585 MB at 4.3 megapixels (the same camera), i.e. 250 MB + 77 bytes per pixel; rounded up for margin.
BYTES_PER_SENSOR_PIXEL = 100
#: a worker process's memory before its first capture (Python, numpy, numba, OpenCV, OpenImageIO)
PROCESS_BASE_BYTES = 250e6
