"""The commands of this tree against those of another revision, side by side on one machine:
``python scripts/bench_commands.py --compare REV [--pairs N]``.

REV's files are exported (``git archive REV``) into a temporary folder, so nothing in the repository changes
and an interrupted run leaves no worktree behind. Every measured command is a fresh ``python -m lfproc``
process of one side's code (the same Python and packages for both), on the Illum-sized capture with its saved
grid (``--calib``), each side with its own decoder cache, made ready by one unmeasured run first. Then N
pairs: in each pair both sides run every command, REV first in even pairs and this tree first in odd ones,
so that a load which drifts during the run weighs on both sides alike.

Reported per command: the median over the pairs of the ratio this tree ÷ REV of wall time and of CPU time
(user + system, all threads), each side's median wall and CPU time, and each side's peak memory (the
largest resident set of its runs). On a loaded machine the CPU ratio is the steadier number; the wall ratio
of alternating pairs cancels a slow drift of the load, not its bursts.
"""

from __future__ import annotations

import shutil
import statistics
import subprocess
import tarfile
import tempfile
from pathlib import Path

#: the commands compared: (label, arguments after the capture, camera and grid)
COMMANDS = (("refocus --a 0:2:0.5", ["refocus", "--a", "0:2:0.5"]),
            ("views", ["views"]))


def export_revision(root: Path, rev: str, into: Path) -> str:
    """REV's files (``git archive``) in ``into``; returns ``"abc1234"``, the commit REV names."""
    commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", f"{rev}^{{commit}}"],
                            capture_output=True, text=True)
    if commit.returncode != 0:
        raise SystemExit(f"--compare {rev}: not a revision of {root} ({commit.stderr.strip()})")
    archive = into / "code.tar"
    with open(archive, "wb") as fh:
        subprocess.run(["git", "-C", str(root), "archive", "--format=tar", rev], stdout=fh, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(into / "code", filter="data")
    archive.unlink()
    return commit.stdout.strip()


def command_argv(folder: Path, arguments: list[str], outdir: Path) -> list[str]:
    """A compared command on the capture of ``folder`` with its saved grid, writing into ``outdir``."""
    return [arguments[0], str(folder / "capture.png"), "--camera", str(folder / "camera.toml"),
            "--calib", str(folder / "grid.json"), *arguments[1:], "-o", str(outdir)]


def compare(root: Path, folder: Path, rev: str, pairs: int, run_command, child_env) -> dict:
    """Run the A/B (module docstring) on the capture in ``folder``; ``run_command`` and ``child_env`` are
    bench_commands' (a fresh process's wall, CPU and peak; the environment that runs one side's code)."""
    work = Path(tempfile.mkdtemp(prefix="lfproc-compare-"))
    try:
        commit = export_revision(root, rev, work)
        sides = {"base": work / "code", "this": root}
        envs = {side: child_env(str(code), folder / f"cache-compare-{side}") for side, code in sides.items()}

        def run(side, arguments):
            outdir = folder / f"o-compare-{side}"
            shutil.rmtree(outdir, ignore_errors=True)
            result = run_command(command_argv(folder, arguments, outdir), envs[side])
            shutil.rmtree(outdir, ignore_errors=True)
            return result

        for side in sides:                       # the decoder caches ready (not measured)
            run(side, COMMANDS[0][1])
        runs = {(label, side): [] for label, _ in COMMANDS for side in sides}
        for pair in range(pairs):
            order = ("base", "this") if pair % 2 == 0 else ("this", "base")
            for label, arguments in COMMANDS:
                for side in order:
                    result = run(side, arguments)
                    runs[label, side].append({"wall_s": result["seconds"], "cpu_s": result["cpu_s"],
                                              "peak_mib": result["peak_bytes"] / 2 ** 20})
                print(f"pair {pair + 1}/{pairs} {label}: " + ", ".join(
                    f"{side} {runs[label, side][-1]['wall_s']:.2f} s (CPU {runs[label, side][-1]['cpu_s']:.2f} s, "
                    f"{runs[label, side][-1]['peak_mib']:.0f} MiB)" for side in ("base", "this")), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
        for side in ("base", "this"):
            shutil.rmtree(folder / f"cache-compare-{side}", ignore_errors=True)
    return {"rev": rev, "commit": commit, "pairs": pairs,
            "commands": [summarise(label, runs[label, "base"], runs[label, "this"]) for label, _ in COMMANDS]}


def summarise(label: str, base: list[dict], this: list[dict]) -> dict:
    """One command's row: median ratios of the pairs, each side's medians and peak, every run kept."""
    def median(rows, key):
        return statistics.median(row[key] for row in rows)

    return {"command": label,
            "wall_ratio": statistics.median(t["wall_s"] / b["wall_s"] for b, t in zip(base, this)),
            "cpu_ratio": statistics.median(t["cpu_s"] / b["cpu_s"] for b, t in zip(base, this)),
            "base": {"wall_s": median(base, "wall_s"), "cpu_s": median(base, "cpu_s"),
                     "peak_mib": max(row["peak_mib"] for row in base)},
            "this": {"wall_s": median(this, "wall_s"), "cpu_s": median(this, "cpu_s"),
                     "peak_mib": max(row["peak_mib"] for row in this)},
            "runs": {"base": base, "this": this}}


def compare_lines(results: dict) -> list[str]:
    """The page's section for each ``--compare`` run (results: REV → :func:`compare`'s result)."""
    lines = []
    for c in results.values():
        lines += ["", f"## Against {c['rev']} (commit {c['commit']}): {c['pairs']} alternating pairs", "",
                  f"`python scripts/bench_commands.py --compare {c['rev']}` on {c.get('date', '?')}"
                  + (f"; {c['note']}" if c.get("note") else "") + ". Ratio = this tree ÷ "
                  f"{c['commit']}, the median over the pairs; times are medians, peaks the largest of the runs.", "",
                  "| command | wall ratio | CPU ratio | wall s (base → this) | CPU s (base → this) | "
                  "peak MiB (base → this) |", "| --- | --- | --- | --- | --- | --- |"]
        for row in c["commands"]:
            b, t = row["base"], row["this"]
            lines.append(f"| `lfproc {row['command']}` | {row['wall_ratio']:.3f} | {row['cpu_ratio']:.3f} | "
                         f"{b['wall_s']:.2f} → {t['wall_s']:.2f} | {b['cpu_s']:.2f} → {t['cpu_s']:.2f} | "
                         f"{b['peak_mib']:.0f} → {t['peak_mib']:.0f} |")
        if c.get("load"):
            lines += ["", f"Load gauge: {c['load']['before']['load_factor']:.1f}× before, "
                          f"{c['load']['after']['load_factor']:.1f}× after (1.0 = an idle core)."]
    return lines
