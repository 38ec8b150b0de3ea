"""The measured numbers quoted in README.md and docs/*.md, each tied to the benchmark JSON it comes from.

A quoted number carries a marker right after it, invisible once rendered::

    | one integer slice | 0.032<!--n:refocus.integer_s--> s | ...
    | Lytro raw | ... | 0.281<!--p:benchmarks-lytro.md--> s | ...

``<!--n:NAME-->``: ``NUMBERS`` below says what the number is and where it is measured: a JSON file in ``docs/``
(written by the benchmark script named in ``SOURCES``) and the value in it. The quote must equal that value
rounded to the digits it shows (``0.032`` for 0.0321…, ``208`` for 207.6, ``1.5`` for 1.46).
``<!--p:PAGE-->``: a number from a generated benchmark page of ``docs/`` that has no JSON yet (calibration,
Lytro unpacking, the microscope z-stack); the page must show the same digits.
``tests/test_doc_numbers.py`` checks every marker, that every number here is quoted somewhere, and that the
benchmark tables (``TABLES``) quote no measured number without a marker, so a rerun of a benchmark (which
rewrites its JSON) shows every quote that moved.

    python scripts/doc_numbers.py          # each quote, its value in the JSON, OK or DRIFT; exit 1 on drift
"""

from __future__ import annotations

import json
import re
import sys
from functools import lru_cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"

#: the JSON files and the scripts that write them
SOURCES = {
    "benchmarks.json": "python scripts/bench.py (every stage on a decoded Illum-like capture, 0.54 GB of views)",
    "benchmarks-commands.json": "python scripts/bench_commands.py --json docs/benchmarks-commands.json (whole commands)",
    "benchmarks-decode.json": "python scripts/bench_decode.py (decoding: bias, colour, memory)",
    "benchmarks-depth.json": "python scripts/bench_depth.py (depth maps of an Illum-sized light field, 0.73 GB)",
    "benchmarks-refocus.json": "python scripts/bench_refocus.py --json docs/benchmarks-refocus.json (refocusing an "
                               "Illum-sized light field, 0.73 GB)",
}


@lru_cache(maxsize=None)
def load(name: str) -> dict:
    return json.loads((DOCS / name).read_text(encoding="utf-8"))


def _commands(*path):
    return lambda: _get(load("benchmarks-commands.json"), path)


def _get(data, path):
    for key in path:
        data = data[key]
    return data


def _refocus(case):
    return lambda: load("benchmarks-refocus.json")["median_s"][case]


def _refocus_check(name):
    return lambda: next(c["value"] for c in load("benchmarks-refocus.json")["checks"] if c["name"] == name)


def _depth(case_index, field):
    return lambda: load("benchmarks-depth.json")["speed"][case_index][field]


def _phase(name):
    return lambda: next(p for p in load("benchmarks-commands.json")["phases"]["phases"] if p["phase"] == name)


#: marker name -> (what the number is, its value from the JSON)
NUMBERS = {
    # refocusing (scripts/bench_refocus.py: 15 x 15 x 434 x 625 x 3 float32, 0.73 GB)
    "refocus.floor_s": ("one read of the views: views.sum(axis=(0, 1))",
                        _refocus("numpy floor: views.sum(axis=(0,1))")),
    "refocus.integer_s": ("one integer slice (a gather)", _refocus("one integer slice")),
    "refocus.integer_gb_s": ("one integer slice, GB of views read per second",
                             lambda: load("benchmarks-refocus.json")["gigabytes"]
                             / load("benchmarks-refocus.json")["median_s"]["one integer slice"]),
    "refocus.integer_per_floor": ("one integer slice / one read", _refocus_check("integer slice / numpy floor")),
    "refocus.nearest_s": ("one real slice, nearest", _refocus("one real slice, nearest")),
    "refocus.linear_s": ("one real slice, linear", _refocus("one real slice, linear")),
    "refocus.cubic_s": ("one real slice, cubic", _refocus("one real slice, cubic")),
    "refocus.five_s": ("five integer slices in one call", _refocus("five integer slices, one call")),
    "refocus.five_per_one": ("five slices in one call / one slice", _refocus_check("five fused / one slice")),
    "refocus.five_separate_s": ("five integer slices, five calls", _refocus("five integer slices, separate calls")),
    "refocus.baseline_s": ("np.pad baseline, integer a", _refocus("np.pad baseline, integer a")),
    "refocus.baseline_per_lfproc": ("np.pad baseline / one integer slice",
                                    _refocus_check("np.pad baseline / integer slice")),
    "refocus.baseline_per_floor": ("np.pad baseline / one read",
                                   lambda: load("benchmarks-refocus.json")["median_s"]["np.pad baseline, integer a"]
                                   / load("benchmarks-refocus.json")["median_s"]["numpy floor: views.sum(axis=(0,1))"]),
    # depth maps (scripts/bench_depth.py: 15 x 15 x 434 x 625 x 3 float32, 0.73 GB)
    "depth.default_s": ("depth map, default search (coarse pass), median of 3", _depth(0, "median_s")),
    "depth.default_per_slice": ("depth map, default search / one refocused slice", _depth(0, "ratio_to_one_slice")),
    "depth.no_coarse_s": ("depth map, no coarse pass, median of 3", _depth(1, "median_s")),
    "depth.no_coarse_per_slice": ("depth map, no coarse pass / one refocused slice", _depth(1, "ratio_to_one_slice")),
    "depth.range_s": ("depth map, --depth-range for a in [0, 1], median of 3", _depth(2, "median_s")),
    "depth.range_per_slice": ("depth map, --depth-range for a in [0, 1] / one refocused slice",
                              _depth(2, "ratio_to_one_slice")),
    "depth.one_slice_s": ("one refocused slice (linear) of the depth benchmark's light field",
                          lambda: load("benchmarks-depth.json")["one_slice_linear_s"]),
    # whole commands (scripts/bench_commands.py: the Illum-like capture, saved calibration, decoder cached)
    "commands.refocus_s": ("lfproc refocus, 5 slices, wall", _commands("commands", 1, "seconds")),
    "commands.views_s": ("lfproc views, 225 TIFFs, wall", _commands("commands", 2, "seconds")),
    "commands.refocus_cpu_s": ("lfproc refocus, CPU", _commands("commands", 1, "cpu_s")),
    "commands.views_cpu_s": ("lfproc views, CPU", _commands("commands", 2, "cpu_s")),
    "commands.refocus_gb": ("lfproc refocus, peak memory (GB)", _commands("commands", 1, "peak_gb")),
    "commands.views_gb": ("lfproc views, peak memory (GB)", _commands("commands", 2, "peak_gb")),
    "commands.decode_s": ("decoding, a phase of lfproc refocus, wall", lambda: _phase("decoding")()["wall_s"]),
    "commands.decode_cpu_s": ("decoding, a phase of lfproc refocus, CPU", lambda: _phase("decoding")()["cpu_s"]),
    "commands.disk_percent": ("writing 225 view TIFFs, % of one tofile of the same bytes",
                              lambda: 100 * load("benchmarks-commands.json")["disk"]["ratio"]),
    "commands.imports_floor_s": ("floor: importing numpy, OpenCV, OpenImageIO and numba in a fresh process",
                                 _commands("floors", "imports_s")),
    "commands.png_floor_s": ("floor: reading the capture PNG with OpenImageIO alone", _commands("floors", "png_read_s")),
    "batch.one_worker_s": ("lfproc batch, 20 captures, 1 worker, per capture",
                           _commands("batch", "workers_1", "per_capture_s")),
    "batch.two_workers_s": ("lfproc batch, 20 captures, 2 workers, per capture",
                            _commands("batch", "workers_2", "per_capture_s")),
    "batch.speedup": ("lfproc batch, 2 workers / 1 worker", _commands("batch", "speedup")),
    "batch.one_thread_s": ("lfproc batch, 20 captures, 1 worker on one thread, per capture",
                           _commands("batch", "workers_1_one_thread", "per_capture_s")),
    "batch.own_threads": ("lfproc batch, 1 worker with its threads / 1 worker on one thread",
                          lambda: load("benchmarks-commands.json")["batch"]["workers_1_one_thread"]["seconds"]
                          / load("benchmarks-commands.json")["batch"]["workers_1"]["seconds"]),
}

MARKER_NAME = re.compile(r"<!--([np]):([\w.-]+)-->")
NUMBER_AT_END = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?)$")     # the number the marker follows directly


#: the benchmark tables: (file, text just above the table, the columns whose measured numbers must all carry a
#: marker, counted from 0)
TABLES = [
    ("docs/benchmarks-refocus.md", "# Refocusing speed", (1, 2)),
    ("docs/benchmarks.md", "The headline numbers", (1, 2)),
]

_CELL_NUMBER = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?)(?![\w.])(?!\s*<!--)")
_UNIT = re.compile(r"\s*(?:s\b|GB\b|MB\b|×|%)")
_EXEMPT = ("≤ ", "≥ ", "target ", "~")


def unmarked() -> list[str]:
    """Measured numbers in the benchmark tables' measured columns without a marker (a decimal number, or any
    number with a unit: s, GB, MB, ×, %); targets (after "≤", "≥", "target") are not measurements."""
    problems = []
    for name, above, columns in TABLES:
        lines = (ROOT / name).read_text(encoding="utf-8").splitlines()
        start = next((k for k, line in enumerate(lines) if above in line), None)
        if start is None:
            problems.append(f"{name}: no table under {above!r}")
            continue
        first = next(k for k in range(start, len(lines)) if lines[k].startswith("|"))
        rows = []
        for k in range(first + 2, len(lines)):
            if not lines[k].startswith("|"):
                break
            rows.append(k)
        for k in rows:
            cells = re.split(r"(?<!\\)\|", lines[k].strip().strip("|"))
            for column in columns:
                cell = re.sub(r"\[([^]]*)\]\([^)]*\)", r"\1", cells[column])     # links: their text only
                for match in _CELL_NUMBER.finditer(cell):
                    number = match.group(1)
                    if cell[:match.start()].endswith(_EXEMPT):
                        continue
                    if "." in number or _UNIT.match(cell, match.end()):
                        problems.append(f"{name}:{k + 1}: {number} in column {column + 1} has no marker "
                                        f"(<!--n:NAME--> from the JSON, or <!--p:PAGE-->)")
    return problems


def documents() -> list[Path]:
    return [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]


def quotes():
    """(file, line number, written number, kind "n" or "p", name) of every marker."""
    for path in documents():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for match in MARKER_NAME.finditer(line):
                before = NUMBER_AT_END.search(line[:match.start()])
                yield path, number, before.group(1) if before else None, match.group(1), match.group(2)


def rounded(value: float, written: str) -> str:
    """``value`` with as many decimals as ``written`` shows."""
    decimals = len(written.split(".")[1]) if "." in written else 0
    return f"{value:.{decimals}f}"


def expected(kind: str, name: str, written: str) -> str | None:
    """What the marker's source says, with the digits of ``written``; None for an unknown source."""
    if kind == "n":
        return rounded(float(NUMBERS[name][1]()), written) if name in NUMBERS else None
    page = DOCS / name
    if not page.is_file():
        return None
    shown = set(re.findall(r"(?<![\w.])\d+(?:\.\d+)?", page.read_text(encoding="utf-8")))
    return written if written in shown else "not on the page"


def check() -> list[str]:
    """One line per problem: an unknown marker, a marker after no number, a quote that is not its source's."""
    problems = []
    for path, line, written, kind, name in quotes():
        where = f"{path.relative_to(ROOT)}:{line}"
        if written is None:
            problems.append(f"{where}: the marker {name!r} follows no number")
            continue
        value = expected(kind, name, written)
        if value is None:
            problems.append(f"{where}: unknown source {name!r} (add it to NUMBERS in scripts/doc_numbers.py, or "
                            f"name a page of docs/)")
        elif value != written:
            problems.append(f"{where}: {name} is quoted as {written}, its source says {value}")
    return problems


def main() -> int:
    for path, line, written, kind, name in quotes():
        what = NUMBERS[name][0] if kind == "n" and name in NUMBERS else f"quoted from docs/{name}"
        value = expected(kind, name, written) if written else None
        status = "OK" if value == written else "DRIFT"
        print(f"{status:5s} {str(path.relative_to(ROOT)) + ':' + str(line):28s} {name:28s} {written or '-':>8s} "
              f"{value or '?':>8s}  {what}")
    problems = check() + unmarked()
    for problem in problems:
        print(problem, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
