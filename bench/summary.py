"""The speed figures in one table: figure, ours, peer, ratio, goal, met or not, and the wall
times beside; printed as Markdown with the load average before and after, written as JSON
(bench/results.json) with the machine and the date, and as the page docs/benchmarks.md
(bench/benchmarks_page.py).

Run: python bench/summary.py [--quick] [--json bench/results.json] (``make bench``);
``--page-only`` rewrites docs/benchmarks.md from the saved JSON without measuring;
BENCH_SMOKE=1 runs every part at tiny sizes (test/bench: a check that nothing rots, not a
measurement). It takes the figures of bench_kinematics, bench_dynamics, bench_batch and
bench_scaling (each checked against Pinocchio or the per-sample functions before it is
timed), times the command line's start-up, and adds the rows of bench/goal_rows.py (the
main job, gripping, inverse mode, right-hand sides, the free arm against MuJoCo, contact
against MuJoCo at matched accuracy, N youBots in a row; rows say "MuJoCo not installed"
without it). Every figure is CPU time (bench/timing.py), ours and the peer alternating in
this process, best of N; ratios are ours / peer in CPU time; "-" where a row has no peer
or no goal.
"""
from __future__ import annotations

import argparse
import datetime
import json
import resource
import subprocess
import sys
from pathlib import Path
from typing import Callable

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_batch import batch_calls  # noqa: E402
from bench_dynamics import arm, dynamics_pairs  # noqa: E402
from bench_kinematics import kinematics_pairs  # noqa: E402
from bench_scaling import scaling  # noqa: E402
from goal_rows import (arm_rows, gripping_rows, inverse_rows, mujoco_rows, rhs_rows, row,  # noqa: E402
                       session_rows, youbot_row_rows)
from benchmarks_page import markdown, write_page  # noqa: E402
from timing import WALL, Timing, best_timings, load_average, machine, sized, smoke  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
#: figure of the bench scripts -> (row name, the largest ratio ours / peer that meets the goal).
#: (issue 25 raised the Jacobian, ID, FD and batch goals met in issue 14)
PER_CALL_GOALS = {
    "PoE FK (space) vs Pinocchio FK": ("PoE FK vs pin FK + frame placement", 4.0),
    "PoE space Jacobian vs WORLD frame Jacobian": ("PoE space Jacobian vs pin WORLD frame Jacobian", 2.0),
    "PoE body Jacobian vs LOCAL frame Jacobian": ("PoE body Jacobian vs pin LOCAL frame Jacobian", 2.0),
    "RNEA + URDF friction vs pin.rnea": ("RNEA + URDF friction vs pin.rnea", 1.5),
    "ABA + URDF friction vs pin.aba": ("ABA + URDF friction vs pin.aba", 1.3),
    "RNEA + mixed friction vs pin.rnea": ("RNEA + LuGre/Stribeck friction vs pin.rnea", 1.5),
    "ABA + mixed friction vs pin.aba": ("ABA + LuGre/Stribeck friction vs pin.aba", 1.3),
    "URDF friction alone vs numpy laws": ("URDF friction alone vs the laws in numpy", 1.0),
}
BATCH_GOAL = 1.1
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
        mine, peer = (t / 1e-6 for t in best_timings([ours, theirs], calls, repeat))
        rows.append(row(label, mine.cpu, peer.cpu, "us", f"ratio <= {goal:g}", mine.cpu / peer.cpu <= goal,
                        wall=(mine.wall, peer.wall)))
    return rows


def batch_rows(samples: int, repeat: int, calls_per_loop: int = 5) -> list[dict]:
    """Each batch function against its peer: the best of ``repeat`` alternating loops of
    ``calls_per_loop`` calls (a loop of several calls: one call of a millisecond is too
    short a sample on a busy machine, its ratio scattered by 10 % between runs)."""
    calls = batch_calls(samples)
    rows = []
    for name, peer in (("inverse", "rneaInParallel"), ("forward", "abaInParallel")):
        for call in calls[name]:
            call()
        times = [t / 1e-3 for t in best_timings(calls[name], calls_per_loop, repeat)]
        rows.append(row(f"{name}_dynamics_batch ({samples} samples) vs pin.{peer} + numpy friction",
                        times[0].cpu, times[1].cpu, "ms", f"ratio <= {BATCH_GOAL:g}",
                        times[0].cpu / times[1].cpu <= BATCH_GOAL, wall=(times[0].wall, times[1].wall)))
        if len(times) > 2:
            # The goal (5x) is against the loop of before issue 14 (23.4 ms in the issue); this
            # loop calls today's per-sample function, itself about 2x faster than that one.
            rows.append(row(f"{name}_dynamics_batch vs today's per-sample loop ({samples} samples)", times[0].cpu,
                            times[2].cpu, "ms", "-", True, wall=(times[0].wall, times[2].wall)))
    return rows


def child_seconds(argv: list[str], repeat: int) -> Timing:
    """Best CPU time (user + system of the child) and best wall time (s) of a fresh
    interpreter running ``argv`` from the repository."""
    cpu = wall = float("inf")
    for _ in range(repeat):
        before, start = resource.getrusage(resource.RUSAGE_CHILDREN), WALL()
        subprocess.run([sys.executable, *argv], cwd=REPO, capture_output=True, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        wall = min(wall, WALL() - start)
        cpu = min(cpu, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return Timing(cpu, wall)


def startup_rows(repeat: int) -> list[dict]:
    """`youbot-dynamics --help` and `info` (through cli.main) against a bare interpreter, in
    CPU time of the child process."""
    bare = child_seconds(["-c", "pass"], repeat)
    rows = []
    for command in ("--help", "info"):
        code = "import sys; from youbot_dynamics.cli import main; sys.exit(main(sys.argv[1:]))"
        ours = child_seconds(["-c", code, command], repeat)
        rows.append(row(f"youbot-dynamics {command} start-up vs python -c pass", ours.cpu, bare.cpu, "s",
                        "ours <= 0.4 s", ours.cpu <= 0.4, wall=(ours.wall, bare.wall)))
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


def measure(quick: bool) -> dict:
    """Every row (BENCH_SMOKE=1: tiny sizes), with the machine, the date and the load average
    before and after: the results that bench/results.json holds."""
    began, load_before = WALL(), load_average()
    repeat = sized(5 if quick else 15, 1)
    calls = sized(300, 5)
    parts: list[tuple[str, Callable[[], list[dict]]]] = [
        ("per call", lambda: per_call_rows(calls, repeat)),
        ("batch", lambda: batch_rows(sized(2000, 20), repeat, sized(5, 1))),
        ("start-up", lambda: startup_rows(sized(3 if quick else 5, 1))),
        ("right-hand side", lambda: rhs_rows(sized(2000, 5), repeat)),
        ("inverse mode", lambda: inverse_rows(sized(3 if quick else 5, 1))),
        ("gripping", gripping_rows),
        ("main job", lambda: session_rows(sized(1 if quick else 2, 1))),
        ("free arm vs MuJoCo", lambda: arm_rows(sized(3 if quick else 5, 1))),
        ("contact vs MuJoCo", mujoco_rows),
        ("N youBots", lambda: youbot_row_rows(sized(1 if quick else 2, 1))),
    ]
    rows: list[dict] = []
    for name, part in parts:
        start = WALL()
        rows += part()
        print(f"{name}: {WALL() - start:.0f} s (load average {load_average()})", file=sys.stderr, flush=True)
    scaled = scaling(dofs=sized((5, 10, 20, 40, 60), (5, 10)), calls=calls, repeat=repeat)
    rows += scaling_rows(scaled)
    return {"machine": machine(), "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "load": {"before": load_before, "after": load_average()}, "seconds": WALL() - began, "rows": rows,
            "scaling": scaled}


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
    results = measure(args.quick)
    print(f"Machine: {results['machine']}\nLoad average (1, 5, 15 min): {results['load']['before']} before, "
          f"{results['load']['after']} after\n\n{markdown(results['rows'])}\n\n({results['seconds']:.0f} s)")
    if smoke():
        print("smoke run (BENCH_SMOKE): nothing written")
        return
    args.json.write_text(json.dumps(results, indent=1) + "\n")
    print(f"written {args.json}")
    print(f"written {write_page(args.json, args.page)}")


if __name__ == "__main__":
    main()
