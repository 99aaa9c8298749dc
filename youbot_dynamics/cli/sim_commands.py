"""Sub-commands `simulate` (run a scene) and `work-precision` (speed versus accuracy on a
scene, with an optional recommendation for a target error, which ``--write-back`` pins into
the scene file)."""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from contextlib import contextmanager
from typing import Callable, Iterator

import numpy as np
from tqdm import tqdm

from youbot_dynamics.accuracy.front import pareto_front, write_front
from youbot_dynamics.accuracy.work_precision import resolve_integrator, work_precision, write_back
from youbot_dynamics.cli.common import (CommandError, add_duration, add_json, add_out_folder,
                                        add_sweep_arguments, add_tolerance_arguments, finite_or_none,
                                        output_file, output_folder, positive, positive_int)
from youbot_dynamics.integrate.integrators import (IntegrationError, StepBudgetError,
                                                   checked_fixed_step, fixed_step_count)
from youbot_dynamics.integrate.registry import INTEGRATORS, REGISTRY, STEPPERS, integrator_names
from youbot_dynamics.io.csv_table import write_csv
from youbot_dynamics.scene.front import with_accuracy
from youbot_dynamics.scene.schema import Scene, find_scene, load_scene
from youbot_dynamics.sim.companion import run
from youbot_dynamics.sim.divergence import MAX_STEPS, PROGRESS_STEPS, DivergenceLimits
from youbot_dynamics.sim.simulator import Simulator

#: The commands here that run an integrator, and where their accuracy comes from (see
#: youbot_dynamics.cli: "--tol" or the reason the command takes none).
ACCURACY = {"simulate": "--tol",
            "work-precision": "it sweeps every integrator over tolerances or steps against a tight reference"}


def add_step_budget_argument(parser: argparse.ArgumentParser) -> None:
    """--max-steps: the budget of a fixed-step run."""
    parser.add_argument("--max-steps", type=positive_int, default=MAX_STEPS, metavar="N",
                        help=f"refuse a fixed-step run of more than N steps (default {MAX_STEPS:g})")


def checked_step_budget(method: str, dt: float | None, times: np.ndarray,
                        max_steps: int) -> float:
    """The steps a fixed-step run over ``times`` takes (0 for adaptive runs); refused in one
    line, before the run, when over ``max_steps`` or when dt cannot move the clock."""
    if dt is None:
        return 0.0
    try:
        checked_fixed_step(method, dt, times, max_steps)
    except StepBudgetError as error:
        raise CommandError(f"{error}: raise --max-steps or dt") from None
    return fixed_step_count(dt, times)


@contextmanager
def progress_bar(command: str, steps: float, t_start: float, t_end: float,
                 enabled: bool) -> Iterator[Callable[[float], None] | None]:
    """A progress bar on stderr over simulated time, for runs of more than PROGRESS_STEPS
    steps (None otherwise: no callback, no cost)."""
    if not enabled or steps <= PROGRESS_STEPS:
        yield None
        return
    with tqdm(total=t_end - t_start, desc=command, unit="s", file=sys.stderr) as bar:
        yield lambda t: bar.update(t - t_start - bar.n)


def add_accuracy_arguments(parser: argparse.ArgumentParser) -> None:
    """--error-estimate and --accuracy E."""
    parser.add_argument("--error-estimate", action="store_true",
                        help="estimate the run's error: a companion run at tol/20 (adaptive) or dt/2 (fixed step, "
                        "Richardson) in a worker process, compared per state group and on event times")
    parser.add_argument("--accuracy", type=positive, metavar="E",
                        help="run the cheapest point of the scene's stored work-precision front whose error is at "
                        "most E (the front's unit; stored by work-precision --write-back)")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add `simulate` and `work-precision`."""
    run = subparsers.add_parser("simulate", help="simulate a scene",
                                description="Simulate a scene (a packaged name such as arm_swing, "
                                "or a YAML path) and print the final state by joint name, the "
                                "integrator statistics and the energy error.")
    run.add_argument("--scene", required=True, metavar="NAME_OR_PATH")
    run.add_argument("--integrator", help=f"override: one of {', '.join(INTEGRATORS + STEPPERS)}, or auto (a sweep "
                     "before the run; pin it with work-precision --write-back)")
    run.add_argument("--dt", type=float, help="step size of a fixed-step integrator, s")
    add_tolerance_arguments(run)
    add_duration(run, default_text="the scene's")
    run.add_argument("--output", metavar="FILE.csv", help="write the trajectory as CSV")
    add_step_budget_argument(run)
    add_accuracy_arguments(run)
    add_json(run)
    run.set_defaults(run=run_simulate)
    study = subparsers.add_parser("work-precision", help="speed versus accuracy on a scene",
                                  description="Sweep every integrator over step sizes or "
                                  "tolerances against a tight reference; write CSV, markdown "
                                  "and PNG; with --target-error recommend the setting of least "
                                  "counted work (rhs evaluations + Jacobians x state dimension) "
                                  "that meets it; with --write-back pin it into the scene file. "
                                  "The error is the final joint-space one (rad), or without robot "
                                  "joints the free bodies' final positions (m); errors below the "
                                  "reference's own accuracy print as '< estimate (ref)'. Scenes with "
                                  "free bodies are measured on their final positions (m), with the event "
                                  "times beside; scenes with constraint-based contact sweep the constraint "
                                  "steppers over dt against the scene's stepper at dt/32.")
    study.add_argument("--scene", required=True, metavar="NAME_OR_PATH")
    study.add_argument("--target-error", type=float, help="final error to meet, rad (m without robot joints) "
                       "(default with --write-back: the scene's integrator.target_error)")
    study.add_argument("--write-back", action="store_true",
                       help="store the sweep's front (the points no other beats on error and work) in the scene "
                       "file's front block, which accuracy: and simulate --accuracy choose from; with a target "
                       "error also pin the recommended method and tolerance (or dt) into its integrator block "
                       "(comments and other keys kept)")
    add_duration(study, default_text="the scene's")
    add_out_folder(study, "the CSV, markdown and PNG", "out/work_precision")
    add_sweep_arguments(study)
    add_json(study)
    study.set_defaults(run=run_work_precision)


def scene_from(args: argparse.Namespace) -> Scene:
    """The scene with the command line's overrides applied (checked like the file's)."""
    scene = load_scene(args.scene)
    if getattr(args, "duration", None) is not None:
        scene = scene.with_duration(args.duration)
    override = [getattr(args, name, None) for name in ("integrator", "dt", "tol", "rtol", "atol")]
    if getattr(args, "accuracy", None) is not None:
        if any(value is not None for value in override):
            raise CommandError("--accuracy chooses the integrator from the scene's stored front: drop --integrator, "
                               "--dt, --tol, --rtol and --atol")
        return with_accuracy(scene, args.accuracy)
    if any(value is not None for value in override):
        scene = dataclasses.replace(scene, accuracy=None, accuracy_choice=None)  # the command line chooses
        method = args.integrator or scene.integrator.method
        fixed = method in REGISTRY and not REGISTRY[method].adaptive
        if args.dt is not None and not fixed:
            fixed_names = ", ".join(integrator_names(adaptive=False))
            raise CommandError(f"--dt applies to fixed-step integrators ({fixed_names}), not {method!r}; "
                               "use --tol or --rtol/--atol")
        if fixed and any(value is not None for value in (args.tol, args.rtol, args.atol)):
            raise CommandError(f"--tol/--rtol/--atol apply to adaptive integrators, not {method!r}; use --dt")
        scene = scene.with_integrator(args.integrator, dt=args.dt, rtol=args.rtol, atol=args.atol,
                                      tol=args.tol)
    return scene


def run_simulate(args: argparse.Namespace) -> int:
    """Run the scene; print final state, statistics and energy error (or JSON)."""
    if args.output:
        output_file(args.output, "--output")  # before the run, not after it
    scene = scene_from(args)
    limits = DivergenceLimits(max_steps=args.max_steps)
    integrator = resolve_integrator(scene, progress=not args.json)
    if integrator is not scene.integrator:
        print(f"integrator auto: the sweep chose {integrator.describe()} for target error "
              f"{scene.integrator.target_error:g} rad (pin it: youbot-dynamics work-precision --scene "
              f"{args.scene} --write-back)", file=sys.stderr)
    if scene.accuracy_choice is not None:
        print(f"accuracy: {scene.accuracy_choice}", file=sys.stderr)
    simulator = Simulator(scene, integrator, limits)
    times = scene.output_times
    steps = checked_step_budget(simulator.integrator.method, simulator.integrator.dt, times,
                                args.max_steps)
    try:
        with progress_bar("simulate", steps, times[0], times[-1], not args.json) as progress:
            result = run(simulator.model, progress=progress, error_estimate=args.error_estimate)
    except IntegrationError as error:
        print(f"youbot-dynamics simulate: {error}", file=sys.stderr)
        return 1
    if args.output:
        write_csv(args.output, *result.columns(scene.outputs.record))
    cost = simulator.rhs_cost()
    if args.json:
        print(json.dumps({"scene": scene.name, "integrator": result.integrator.describe(),
                          "t_end": float(result.t[-1]), "final_state": result.final_state,
                          "energy_error": result.energy_error, "conservative": result.conservative,
                          "rhs_cost": cost, "stats": result.stats.as_dict(),
                          "contact_events": [e.as_dict() for e in result.contact_events],
                          "max_penetration": result.max_penetration,
                          "energy_dissipated": result.energy_dissipated,
                          "accuracy": None if scene.accuracy is None else {"target": scene.accuracy,
                                                                           "choice": scene.accuracy_choice},
                          "error_estimate": None if result.error_estimate is None else
                          result.error_estimate.as_dict()}))
        return 0
    print(f"scene {scene.name}: {result.integrator.describe()}, t = {result.t[-1]:g} s, "
          f"state dimension {cost['state_dim']} (nv {cost['nv']}, friction {cost['friction_laws']}, "
          f"controller {cost['controller']})")
    print("final state:")
    for name, value in result.final_state.items():
        print(f"  {name:28s} {value: .9g}")
    print("energy error max|E-E0|: " + (f"{result.energy_error:.3e} J" if result.conservative
                                        else "n/a (friction or a controller changes the energy)"))
    if result.energy_dissipated is not None:
        print(f"energy dissipated E(0)-E(end): {result.energy_dissipated:.6g} J "
              "(passive scene: friction, damping and contact losses; checked >= -energy_tolerance)")
    if result.contact_events or result.max_penetration is not None:
        print(f"contact events: {len(result.contact_events)}, max penetration {result.max_penetration or 0.0:.3e} m")
        for event in result.contact_events[:20]:
            print(f"  t={event.time:.6f} s  {event.pair:24s} {event.kind:10s} {event.value:.6g}")
    print(f"statistics: {result.stats.summary()}")
    if result.error_estimate is not None:
        print("\n".join(result.error_estimate.summary()))
    if args.output:
        print(f"trajectory written to {args.output}")
    return 0


def run_work_precision(args: argparse.Namespace) -> int:
    """Sweep, write the files, print where they are and the recommendation."""
    output_folder(args.out, "--out")
    scene = scene_from(args)
    if args.write_back:
        if args.duration is not None:
            raise CommandError("--write-back stores the front of the scene as its file states it: drop --duration")
        if args.target_error is None:
            args.target_error = scene.integrator.target_error
    study = work_precision(scene, args.out, target_error=args.target_error, progress=not args.json,
                           workers=args.workers, scheduler=args.scheduler)
    best = study.best
    pinned = None
    if args.write_back:
        write_front(find_scene(args.scene), study.reference, study.points)
    if args.write_back and args.target_error is not None:
        if best is None:
            print(f"youbot-dynamics work-precision: no swept setting reaches {args.target_error:g} rad: "
                  f"{scene.source} left unchanged", file=sys.stderr)
            return 1
        pinned = dataclasses.replace(best.spec, energy_tolerance=scene.integrator.energy_tolerance,
                                     target_error=args.target_error)
        write_back(find_scene(args.scene), pinned,
                   f"least counted work (rhs + Jacobians x {study.reference.state_dim}) {best.work:.6g} "
                   f"for target_error {args.target_error:g} rad")
    if args.json:
        print(json.dumps({"scene": scene.name, "reference": study.reference.spec.describe(),
                          "reference_error_estimate": study.reference.error_estimate,
                          "files": [str(f) for f in study.files],
                          "recommendation": None if best is None else best.spec.describe(),
                          "written_back": str(find_scene(args.scene)) if args.write_back else None,
                          "pinned": None if pinned is None else pinned.describe(),
                          "points": [{k: finite_or_none(v) if isinstance(v, float) else v
                                      for k, v in dataclasses.asdict(p).items()} for p in study.points]}))
        return 0
    print(study.files[1].read_text(encoding="utf-8"))
    print("written: " + ", ".join(str(f) for f in study.files))
    if args.write_back:
        print(f"front of {len(pareto_front(study.points))} points stored in {find_scene(args.scene)}")
    if pinned is not None:
        print(f"pinned {pinned.describe()} into {find_scene(args.scene)}")
    return 0
