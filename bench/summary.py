"""The speed figures in one table: figure, ours, peer, ratio, goal, met or not; printed as
Markdown, written as JSON (bench/results.json) with the machine and the date, and as the page
docs/benchmarks.md (bench/benchmarks_page.py).

Run: python bench/summary.py [--quick] [--json bench/results.json] (``make bench``);
``--page-only`` rewrites docs/benchmarks.md from the saved JSON without measuring. It
takes the figures of bench_kinematics, bench_dynamics, bench_batch and bench_scaling (each
checked against Pinocchio or the per-sample functions before it is timed), times the
command line's start-up, and adds the rows of bench/goal_rows.py: the right-hand sides of
arm_friction and arm_ptp, inverse mode per sample, gripping's real-time factor and step
cost, the main job's real-time factor with logs, and contact against MuJoCo at equal
accuracy (rows say "MuJoCo not installed" without it). Per-call figures are the best of
alternating loops (see bench/timing.py), so ours and the peer see the same machine load;
ratios are ours / peer; "-" where a row has no peer or no goal.
"""
from __future__ import annotations

import argparse
import datetime
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_batch import batch_calls  # noqa: E402
from bench_dynamics import arm, dynamics_pairs  # noqa: E402
from bench_kinematics import kinematics_pairs  # noqa: E402
from bench_scaling import scaling  # noqa: E402
from goal_rows import gripping_rows, inverse_rows, mujoco_rows, rhs_rows, row, session_rows  # noqa: E402
from benchmarks_page import markdown, write_page  # noqa: E402
from timing import best_per_call, machine  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
#: figure of the bench scripts -> (row name, the largest ratio ours / peer that meets the goal).
PER_CALL_GOALS = {
    "PoE FK (space) vs Pinocchio FK": ("PoE FK vs pin FK + frame placement", 4.0),
    "PoE space Jacobian vs WORLD frame Jacobian": ("PoE space Jacobian vs pin WORLD frame Jacobian", 6.0),
    "PoE body Jacobian vs LOCAL frame Jacobian": ("PoE body Jacobian vs pin LOCAL frame Jacobian", 6.0),
    "RNEA + URDF friction vs pin.rnea": ("RNEA + URDF friction vs pin.rnea", 2.0),
    "ABA + URDF friction vs pin.aba": ("ABA + URDF friction vs pin.aba", 1.6),
    "RNEA + mixed friction vs pin.rnea": ("RNEA + LuGre/Stribeck friction vs pin.rnea", 2.0),
    "ABA + mixed friction vs pin.aba": ("ABA + LuGre/Stribeck friction vs pin.aba", 1.6),
    "URDF friction alone vs numpy laws": ("URDF friction alone vs the laws in numpy", 1.0),
}
#: Growth in the number of joints: linear like Pinocchio's when ours is at most 1.1 or at most
#: Pinocchio's own exponent + 0.1 (both fits see the same caches and the same load).
LINEAR, SLACK = 1.1, 0.1


def per_call_rows(calls: int, repeat: int) -> list[dict]:
    rows = []
    for name, (ours, theirs) in {**kinematics_pairs(), **dynamics_pairs(arm())}.items():
        if name not in PER_CALL_GOALS:
            continue
        label, goal = PER_CALL_GOALS[name]
        ours(), theirs()  # compile / warm up
        t_ours, t_peer = (t * 1e6 for t in best_per_call([ours, theirs], calls, repeat))
        rows.append(row(label, t_ours, t_peer, "us", f"ratio <= {goal:g}", t_ours / t_peer <= goal))
    return rows


def batch_rows(samples: int, repeat: int) -> list[dict]:
    calls = batch_calls(samples)
    rows = []
    for name, peer in (("inverse", "rneaInParallel"), ("forward", "abaInParallel")):
        for call in calls[name]:
            call()
        times = [t * 1e3 for t in best_per_call(calls[name], 1, repeat)]
        rows.append(row(f"{name}_dynamics_batch ({samples} samples) vs pin.{peer} + numpy friction",
                        times[0], times[1], "ms", "ratio <= 1.3", times[0] / times[1] <= 1.3))
        if len(times) > 2:
            # The goal (5x) is against the loop of before issue 14 (23.4 ms in the issue); this
            # loop calls today's per-sample function, itself about 2x faster than that one.
            rows.append(row(f"{name}_dynamics_batch vs today's per-sample loop ({samples} samples)", times[0],
                            times[2], "ms", "-", True))
    return rows


def wall_seconds(argv: list[str], repeat: int) -> float:
    """Best wall time (s) of a fresh interpreter running ``argv`` from the repository."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run([sys.executable, *argv], cwd=REPO, capture_output=True, check=True)
        best = min(best, time.perf_counter() - start)
    return best


def startup_rows(repeat: int) -> list[dict]:
    """`youbot-dynamics --help` and `info` (through cli.main) against a bare interpreter."""
    bare = wall_seconds(["-c", "pass"], repeat)
    rows = []
    for command in ("--help", "info"):
        code = "import sys; from youbot_dynamics.cli import main; sys.exit(main(sys.argv[1:]))"
        seconds = wall_seconds(["-c", code, command], repeat)
        rows.append(row(f"youbot-dynamics {command} start-up vs python -c pass", seconds, bare, "s",
                        "ours <= 0.4 s", seconds <= 0.4))
    return rows


def scaling_rows(results: dict[str, dict]) -> list[dict]:
    rows = []
    for name, figure in results.items():
        dofs = "-".join(str(n) for n in (figure["dofs"][0], figure["dofs"][-1]))
        ours, theirs = figure["exponent_ours"], figure["exponent_pinocchio"]
        rows.append(row(f"growth exponent in joints ({dofs}): {name}", ours, theirs, "",
                        f"ours <= max({LINEAR}, peer + {SLACK})", ours <= max(LINEAR, theirs + SLACK)))
        rows.append(row(f"{name} at {figure['dofs'][-1]} joints vs Pinocchio", figure["ours_us"][-1],
                        figure["pinocchio_us"][-1], "us", "-", True))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats (a rougher table in seconds)")
    parser.add_argument("--json", type=Path, default=REPO / "bench" / "results.json")
    parser.add_argument("--page", type=Path, default=REPO / "docs" / "benchmarks.md",
                        help="the Markdown page written from the JSON (default docs/benchmarks.md)")
    parser.add_argument("--page-only", action="store_true",
                        help="rewrite the page from the saved JSON, measure nothing")
    args = parser.parse_args()
    if args.page_only:
        print(f"written {write_page(args.json, args.page)}")
        return
    start = time.perf_counter()
    repeat = 5 if args.quick else 15
    parts: list[tuple[str, Callable[[], list[dict]]]] = [
        ("per call", lambda: per_call_rows(300, repeat)),
        ("batch", lambda: batch_rows(2000, max(3, repeat // 2))),
        ("start-up", lambda: startup_rows(3 if args.quick else 5)),
        ("right-hand side", lambda: rhs_rows(2000, repeat)),
        ("inverse mode", lambda: inverse_rows(3 if args.quick else 5)),
        ("gripping", gripping_rows),
        ("main job", lambda: session_rows(1 if args.quick else 2)),
        ("contact vs MuJoCo", mujoco_rows),
    ]
    rows: list[dict] = []
    for name, part in parts:
        began = time.perf_counter()
        rows += part()
        print(f"{name}: {time.perf_counter() - began:.0f} s", file=sys.stderr, flush=True)
    scaled = scaling(calls=300, repeat=repeat)
    rows += scaling_rows(scaled)
    described = machine()
    table = markdown(rows)
    print(f"Machine: {described}\n\n{table}\n\n({time.perf_counter() - start:.0f} s)")
    args.json.write_text(json.dumps({"machine": described, "date": datetime.datetime.now(datetime.timezone.utc)
                                     .isoformat(timespec="seconds"), "rows": rows, "scaling": scaled}, indent=1) + "\n")
    print(f"written {args.json}")
    print(f"written {write_page(args.json, args.page)}")


if __name__ == "__main__":
    main()
