"""The error estimate against the true error: every registry integrator that runs the case,
at three settings, on arm_swing, the elastic pendulum (k = 1000), ball_drop and gripping
(the cases: youbot_dynamics.studies.estimate_table; the method: docs/accuracy.md). Prints
a markdown table and exits 1 if a resolved row is beyond a factor 3; ``--fast`` runs the
test's subset.

Run: python bench/bench_error_estimate.py [--fast] [--case NAME ...]
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
from youbot_dynamics.accuracy.estimate_check import markdown, summary_markdown  # noqa: E402
from youbot_dynamics.studies.estimate_table import CASES, FAST, table  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fast", action="store_true", help="the test's subset")
    parser.add_argument("--case", nargs="*", choices=list(CASES), help="only these cases")
    args = parser.parse_args()
    cases = FAST if args.fast else CASES
    cases = {k: v for k, v in cases.items() if not args.case or k in args.case}
    start = time.process_time()
    rows = table(cases)
    print(markdown(rows))
    print(summary_markdown(rows))
    judged = [r for r in rows if r.failure is None and r.resolved and not math.isnan(r.ratio)]
    print(f"CPU time {time.process_time() - start:.1f} s (this process; the companions ran in workers)")
    return 0 if all(r.within for r in judged) else 1


if __name__ == "__main__":
    sys.exit(main())
