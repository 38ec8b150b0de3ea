"""Figures (matplotlib, imported only when a plot is asked for)."""

from __future__ import annotations

import math


from .atomic import atomic_path
from .errors import LfprocError


def require_matplotlib():
    """Import matplotlib with the Agg backend, or explain how to install it."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise LfprocError("plotting needs matplotlib; install it with: pip install 'lfproc[plot]'") from None
    return plt


def plot_slices(camera, slices, path: str) -> None:
    """Each slice's central distance and DOF interval against a (the paper's Fig. 9), written atomically."""
    plt = require_matplotlib()
    recs = slices.records()
    finite = [r["far_mm"] for r in recs if math.isfinite(r["far_mm"])] + \
             [r["near_mm"] for r in recs if math.isfinite(r["near_mm"])]
    top = max(finite) * 1.15 if finite else 1.0
    fig, ax = plt.subplots(figsize=(7, 4), dpi=120)
    for r in recs:
        near = r["near_mm"] if math.isfinite(r["near_mm"]) else top
        far = r["far_mm"] if math.isfinite(r["far_mm"]) else top
        ax.plot([r["a"], r["a"]], [near, far], color="tab:blue", lw=6, alpha=0.45, solid_capstyle="butt")
        if math.isfinite(r["distance_mm"]):
            ax.plot(r["a"], r["distance_mm"], "o", color="tab:red", ms=4)
    ax.set_xlabel("refocus parameter a")
    ax.set_ylabel("distance from sensor [mm]")
    ax.set_title(f"{camera.name or 'camera'}: slice distance (dot) and DOF (bar); bars at the top reach infinity")
    ax.set_ylim(0, top)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return None


