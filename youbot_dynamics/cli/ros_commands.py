"""Sub-commands that run ROS 2 nodes: ``replay`` and ``main-job``.

- ``replay BAG [--time-scale X] [--topic T ...] [--wait-for TOPIC]``: publish a bag's
  messages on their topics with the recorded timing, X recorded seconds per wall second
  (default 1; 0: as fast as possible, driving /clock; see
  :mod:`youbot_dynamics.ros.replay_node`).
- ``main-job [--scene NAME] [--duration S] [--out DIR] [--rate HZ] [--time-scale X] [--error-estimate]``: the
  dynamics node in simulate mode on the scene (default ``gripping``: two youBots hand a
  wooden sphere over, chosen because it runs faster than real time with logging), paced at
  X simulated seconds per wall second (default 1; 0: as fast as possible), for S simulated seconds
  (default the scene's own duration), publishing on ROS 2 topics and writing
  DIR/<scene>.mcap and DIR/<scene>.rrd; prints the real-time factor, the integrator
  statistics (n/a for a counter the integrator does not report), the energy error, the
  free bodies and contact events (scenes with contact), the error estimate (with
  ``--error-estimate``: youbot_dynamics.sim.error_estimate) and the file paths.

Both take ``--json`` (one JSON object instead of the text). ROS 2 (in youbot_dynamics.ros)
is imported when a command runs, so the rest of the command line works without it.
"""
from __future__ import annotations

import argparse
import math
import time

from youbot_dynamics.cli.common import (CommandError, add_duration, add_json, add_out_folder, add_rate,
                                        add_time_scale, output_folder, print_json, table)
from youbot_dynamics.model import limits

DEFAULT_SCENE = "gripping"
#: The commands here that run an integrator, and where their accuracy comes from (see
#: youbot_dynamics.cli: "--tol" or the reason the command takes none).
ACCURACY = {"main-job": "the scene's integrator block, as the node runs it (simulate --tol tries another; "
                        "work-precision --write-back pins one)"}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `replay` and `main-job`."""
    replay = subparsers.add_parser("replay", help="publish a recorded bag on its ROS 2 topics",
                                   description="Publish a bag's messages on their topics with the recorded "
                                   "timing, scaled by --time-scale, driving /clock. As fast as possible "
                                   "(--time-scale 0) its topics are reliable, keep-all: it waits for slow readers, "
                                   "so a keep-all subscriber (the inverse-mode node) gets every message, and it waits "
                                   "for their acknowledgements (up to 30 s) before leaving.")
    replay.add_argument("bag", help=".mcap file or rosbag2 folder (with metadata.yaml)")
    add_time_scale(replay, "recorded")
    replay.add_argument("--topic", action="append", default=[], help="replay only this topic (repeatable)")
    replay.add_argument("--wait-for", default="", metavar="TOPIC",
                        help="wait up to 30 s for a subscriber on TOPIC before starting")
    add_json(replay)
    replay.set_defaults(run=run_replay)

    job = subparsers.add_parser("main-job", help="simulate a scene with the dynamics node, log MCAP and Rerun")
    job.add_argument("--scene", default=DEFAULT_SCENE, help=f"scene name or file (default {DEFAULT_SCENE})")
    add_duration(job, default_text="the scene's own")
    add_out_folder(job, "the logs", "out")
    add_rate(job, 500.0, "publish rate (samples per simulated second)")
    add_time_scale(job, "simulated")
    job.add_argument("--error-estimate", action="store_true",
                     help="estimate the run's error: the node's companion run (tol/20, or dt/2 with Richardson's "
                     "factor) in a worker process; in the summary and /diagnostics")
    add_json(job)
    job.set_defaults(run=run_main_job)


def run_replay(args: argparse.Namespace) -> int:
    """Replay the bag once; print how many messages went out, how fast, on which topics."""
    from youbot_dynamics.io.bag_reader import bag_topics

    bag_topics(args.bag)  # a file that is no bag: a one-line error before ROS 2 starts
    from youbot_dynamics.ros.replay_node import replay_once

    start = time.monotonic()
    count, bag, topics = replay_once([], bag=args.bag, time_scale=args.time_scale, topics=args.topic,
                                     wait_for=args.wait_for)
    wall = time.monotonic() - start
    if args.json:
        print_json({"messages": count, "bag": str(bag), "wall_time": wall, "topics": list(topics)})
        return 0
    print(f"replay: {count} messages from {bag} in {wall:.3f} s on {', '.join(topics)}")
    return 0


def _contact_rows(values: dict[str, object]) -> list[tuple[str, str]]:
    """Summary rows of a scene with contact, from the /diagnostics values of its session."""
    if not values:
        return []
    kinds = ", ".join(f"{key.rsplit('.', 1)[1]} {count}" for key, count in values.items()
                      if key.startswith("contact.events."))
    return [("free bodies", f"{values['free_bodies'] or 'none'} (on /tf and /free_bodies)"),
            ("contact events", f"{values['contact.events']}{f' ({kinds})' if kinds else ''}; "
                               f"last: {values['contact.last_event']}")]


def _estimate_rows(session) -> list[tuple[str, str]]:
    """The error estimate's summary rows (none without it): every chunk's companion drawn."""
    estimate = session.error_estimate(wait=True)
    if estimate is None:
        return []
    return [("error estimate", line.strip()) for line in estimate.summary()]


def run_main_job(args: argparse.Namespace) -> int:
    """Run the dynamics node on the scene with MCAP and Rerun logs; print the summary table
    (exit 1 if the simulation failed, 2 for bad parameters)."""
    from youbot_dynamics.ros.dynamics_node import run
    from youbot_dynamics.scene.schema import load_scene

    scene = load_scene(args.scene)
    duration = scene.duration if args.duration is None else args.duration
    if not (math.isfinite(duration) and duration > 0):
        raise CommandError(f"--duration must be positive and finite, got {duration}")
    if not (math.isfinite(args.rate) and args.rate > 0):
        raise CommandError(f"--rate must be positive and finite, got {args.rate}")
    problem = limits.samples_problem(duration, args.rate)
    if problem:
        raise CommandError(f"--duration and --rate: {problem}")
    out = output_folder(args.out, "--out")  # before the run: a file in the way, no permission
    paths = {"mcap_path": str(out / f"{scene.name}.mcap"), "rrd_path": str(out / f"{scene.name}.rrd")}
    start = time.monotonic()
    status, node = run(args=[], overrides={"scene": args.scene, "mode": "simulate", "duration": duration,
                                           "publish_rate": args.rate, "time_scale": args.time_scale,
                                           "error_estimate": args.error_estimate, **paths})
    wall = time.monotonic() - start
    if node is None:
        return status
    session = node.session
    if args.json:
        print_json(_summary_record(session, args.rate, wall))
    else:
        print(table(("main job", ""), _summary_rows(session, args.rate, wall)))
    return 1 if session.failure else status


def _summary_rows(session, rate: float, wall: float) -> list[tuple[str, str]]:
    """The main job's summary table: ``session`` (a finished SimulationSession) published at
    ``rate`` Hz in ``wall`` seconds."""
    energy_error = (f"{session.energy_error:.3e} J (max |E(t) - E(0)|)" if session.simulator.conservative else
                    "n/a: the scene's controller, friction or contact change the energy "
                    f"(E(0) = {session.energy0:.6g} J, E(end) = {session.snapshot.energy:.6g} J)")
    return [("scene", f"{session.scene.name} ({session.scene.source})"),
            ("simulated time", f"{session.t:.3f} s at {rate:g} Hz ({session.k + 1} samples per topic)"),
            ("real-time factor", f"{session.t / wall:.3f} (simulated s per wall s, node start to finish)"),
            ("integrator", f"{session.simulator.stats.summary()} (integrator only)"),
            ("energy error", energy_error),
            *_contact_rows(session.contact_values()),
            *_estimate_rows(session),
            ("status", session.failure or "ok"),
            *((f"log ({path.suffix[1:]})", str(path)) for path in session.recorder.paths)]


def _summary_record(session, rate: float, wall: float) -> dict[str, object]:
    """The figures of :func:`_summary_rows` as JSON-ready data (s, Hz, J; energy_error null
    when the scene does not conserve energy)."""
    conservative = session.simulator.conservative
    return {"scene": session.scene.name, "source": str(session.scene.source), "simulated_time": session.t,
            "rate": rate, "samples_per_topic": session.k + 1, "wall_time": wall,
            "real_time_factor": session.t / wall, "integrator": session.simulator.stats.as_dict(),
            "conservative": conservative, "energy_error": session.energy_error if conservative else None,
            "energy_start": session.energy0, "energy_end": session.snapshot.energy,
            "contact": session.contact_values(), "status": session.failure or "ok",
            "error_estimate": None if (estimate := session.error_estimate(wait=True)) is None else estimate.as_dict(),
            "logs": [str(path) for path in session.recorder.paths]}
