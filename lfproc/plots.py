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
    """Write :func:`slice_figure` to ``path`` (PNG, atomically)."""
    plt = require_matplotlib()
    fig = slice_figure(camera, slices)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def slice_figure(camera, slices):
    """Each slice's central distance and DOF interval against a (the paper's Fig. 9), and the DOF itself.

    Distances go on a logarithmic axis, so a 10 mm DOF at 200 mm and a 2 m one at 5 m are both
    visible; intervals reaching infinity end in an arrow at the top.
    """
    plt = require_matplotlib()
    recs = slices.records()
    finite = [r[k] for r in recs for k in ("near_mm", "distance_mm", "far_mm") if math.isfinite(r[k])]
    if finite:
        bottom, top = min(finite) / 1.25, max(finite) * 2.0
    else:
        front = camera.main_optics.usable_range(camera).high_position   # the nearest any slice focuses
        bottom, top = front, front * 100.0
    fig, (ax, ax_dof) = plt.subplots(2, 1, figsize=(7.5, 6.0), dpi=100, sharex=True,
                                     gridspec_kw=dict(height_ratios=(3, 2)))
    for r in recs:
        near = r["near_mm"] if math.isfinite(r["near_mm"]) else top
        far = r["far_mm"] if math.isfinite(r["far_mm"]) else top
        ax.plot([r["a"], r["a"]], [near, far], color="tab:blue", lw=5, alpha=0.45, solid_capstyle="butt")
        ax.plot([r["a"], r["a"]], [near, far], "_", color="tab:blue", ms=9)
        if math.isinf(r["far_mm"]):
            ax.plot(r["a"], top, marker="^", color="tab:blue", ms=7)
        if math.isfinite(r["distance_mm"]):
            ax.plot(r["a"], r["distance_mm"], ".", color="tab:red", ms=4)
    ax.set_yscale("log")
    ax.set_ylim(bottom, top * 1.05)
    ax.set_ylabel("distance from sensor [mm]")
    ax.set_title(f"{camera.name or 'camera'}: slice distance (dot) and depth of field (bar)\n"
                 f"a triangle at the top: the DOF reaches infinity", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    widths = [(r["a"], r["dof_mm"]) for r in recs if math.isfinite(r["dof_mm"]) and r["dof_mm"] > 0]
    if widths:
        ax_dof.plot(*zip(*widths), "o-", color="tab:blue", ms=4, lw=1)
        ax_dof.set_yscale("log")
    infinite = [r["a"] for r in recs if math.isinf(r["dof_mm"])]
    if infinite:
        level = max([w for _, w in widths], default=1.0) * 1.5
        ax_dof.plot(infinite, [level] * len(infinite), "^", color="tab:blue", ms=7, label="infinite DOF")
        ax_dof.legend(loc="upper right", fontsize=8)
    ax_dof.set_ylabel("DOF [mm]")
    ax_dof.set_xlabel("refocus parameter a")
    ax_dof.grid(alpha=0.3, which="both")
    fig.tight_layout()
    return fig
