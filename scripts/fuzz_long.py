"""The long fuzz run of every reader and parser (tests/test_fuzz_readers.py), with fresh randomness.

CI runs a bounded, derandomized number of examples per target; this script runs rounds of
``--examples`` random examples per target until ``--minutes`` have passed, and reports how many inputs
each target was given, how many it refused with LfprocError, and how many escaped (any other
exception, a hang past the per-example deadline, or an allocation the file's size cannot justify):
a failing round stops the run and names the failing test with Hypothesis's reproduction line.

    nice -n 19 python scripts/fuzz_long.py --minutes 5 --json fuzz-long.json

Run from the repository root (PYTHONPATH=. for a checkout).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


class _Failures:
    """A pytest plugin that collects the failing tests of a round."""

    def __init__(self):
        self.failed = []

    def pytest_runtest_logreport(self, report):
        if report.failed:
            self.failed.append((report.nodeid, str(report.longrepr)[-3000:]))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=5.0, help="how long to fuzz (default 5)")
    parser.add_argument("--examples", type=int, default=300, help="examples per target per round (default 300)")
    parser.add_argument("--json", metavar="PATH", help="also write the report as JSON")
    args = parser.parse_args(argv)

    import pytest

    os.environ["LFPROC_FUZZ_EXAMPLES"] = str(args.examples)
    os.environ["LFPROC_FUZZ_RANDOM"] = "1"
    start, rounds, failed = time.monotonic(), 0, []
    while time.monotonic() - start < 60 * args.minutes and not failed:
        plugin = _Failures()
        pytest.main(["-q", "-p", "no:cacheprovider", "-x", str(ROOT / "tests" / "test_fuzz_readers.py")],
                     plugins=[plugin])
        rounds += 1
        failed = plugin.failed
    stats = sys.modules["test_fuzz_readers"].STATS
    tried = sum(c["tried"] for c in stats.values())
    refused = sum(c["refused"] for c in stats.values())
    report = {"minutes": round((time.monotonic() - start) / 60, 2), "rounds": rounds,
              "examples_per_target_per_round": args.examples, "inputs_tried": tried,
              "read": tried - refused, "refused_with_LfprocError": refused, "escaped": len(failed),
              "targets": stats, "failures": failed}
    print(f"\n{tried} inputs in {report['minutes']} min ({rounds} rounds): {tried - refused} read, {refused} "
          f"refused with LfprocError, {len(failed)} escaped")
    for target, counts in sorted(stats.items()):
        print(f"  {target:34s} {counts['tried']:7d} tried {counts['refused']:7d} refused")
    for nodeid, text in failed:
        print(f"ESCAPED: {nodeid}\n{text}")
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=2) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
