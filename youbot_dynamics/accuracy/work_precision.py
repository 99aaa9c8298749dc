"""Speed versus accuracy on a scene: reference, sweep, tables, plot, recommendation.

- Reference: a tight-tolerance high-order run (DOP853 at rtol 1e-12, or Radau for scenes
  whose own integrator is implicit, i.e. stiff ones), checked by a second run at ten times
  the tolerance: their difference bounds the reference's own error (reported, and every
  sweep point is only as trustworthy as that figure).
- Sweep: each integrator over a grid of step sizes (fixed-step methods) or tolerances
  (adaptive ones, atol = rtol / 100). Per point: the final-state error in joint space
  (max_i |q_i - q_ref,i|, rad; a scene with free bodies: of their final positions,
  max_b |p_b - p_ref,b|, m) and of the end-effector position (|p - p_ref|, m), the largest
  difference of matching contact-event times (s), for a single bouncing sphere
  (``ball_drop``) the error of the apex after its first impact (m,
  :func:`~youbot_dynamics.accuracy.bounce.bounce_apex`; the error column is then the larger
  of it and the final-position error, :data:`APEX_MEASURE`; a run with no bounce errs
  infinitely), whether that error is below the reference's own error estimate
  (then it is not resolved: the table prints ``< estimate (ref)``), the
  maximum energy drift max_t |E(t) - E(0)| (J) where the scene conserves energy, the wall
  time (s), the rhs and Jacobian evaluations, the counted work (:func:`counted_work`) and
  the failure (a DivergenceError, IntegrationError or UserInputError message: a method
  that cannot run the scene) if the run failed. The
  energy-growth check is off during the sweep (a drifting run is a data point, not a
  failure); non-finite states and the velocity bound stay on.
- Scenes with constraint-based contact (law ``constraint``): only the constraint steppers
  integrate them, so they are swept over dt (:data:`STEPPER_GRID`) against the scene's own
  stepper at dt / STEPPER_REFINEMENT (checked at twice that step).
- Output: CSV, markdown table and a PNG work-precision plot (matplotlib Agg).
- ``recommend``: the point of least counted work whose joint-space error meets a target
  (ties: registry order, then the looser setting). Counts, not wall time, so that the same
  scene file chooses the same method on any machine; wall time is reported beside.
- ``integrator: auto`` is an offline choice: :func:`write_back` pins the recommendation
  into the scene file (``work-precision --write-back``), editing only its ``integrator``
  block so every comment stays; :func:`resolve_integrator` sweeps for a one-off
  ``simulate`` of an ``auto`` scene. Nothing is cached. The whole front is stored by
  :mod:`youbot_dynamics.accuracy.front`.
"""
from __future__ import annotations

import csv
import dataclasses
import math
import os
import re
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from youbot_dynamics.accuracy.bounce import bounce_apex, is_single_sphere
from youbot_dynamics.accuracy.sweeps import map_cases
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import IntegrationError
from youbot_dynamics.integrate.registry import AUTO, REGISTRY, STEPPERS, integrator_names, is_fixed_step
from youbot_dynamics.scene.reader import read_yaml
from youbot_dynamics.scene.schema import IntegratorSpec, Scene, SceneError
from youbot_dynamics.sim.error_estimate import event_time_difference
from youbot_dynamics.sim.simulator import SimulationResult, Simulator
from youbot_dynamics.sim.state import ContactEvent

#: Step sizes (s) of the fixed-step methods and tolerances of the adaptive ones (every
#: adaptive ODE and DAE integrator of the registry).
DEFAULT_GRID: dict[str, tuple[float, ...]] = {
    "euler": (1e-3, 3e-4, 1e-4, 3e-5),
    "symplectic_euler": (1e-3, 3e-4, 1e-4, 3e-5),
    "rk4": (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4),
    **{name: (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
       for name in integrator_names(("ode", "dae"), adaptive=True)},
}
REFERENCE_RTOL = 1e-12
#: Scenes with constraint-based contact: the steppers over their step (s); the reference is
#: the scene's own stepper at its dt / STEPPER_REFINEMENT (no ODE integrates such contact).
STEPPER_GRID: dict[str, tuple[float, ...]] = {name: (4e-3, 2e-3, 1e-3, 5e-4) for name in STEPPERS}
STEPPER_REFINEMENT = 32
ATOL_PER_RTOL = 1e-2


def spec_for(method: str, value: float) -> IntegratorSpec:
    """The settings of one sweep point: dt = value (fixed step, constraint steppers too) or
    rtol = value, atol = value / 100; energy-growth check off."""
    if is_fixed_step(method):
        return IntegratorSpec(method, dt=value, energy_tolerance=math.inf)
    return IntegratorSpec(method, rtol=value, atol=value * ATOL_PER_RTOL, energy_tolerance=math.inf)


#: What the error column measures: a robot's joint positions, else the free bodies' positions.
JOINT_MEASURE = "max |q - q_ref| (rad)"
BODY_MEASURE = "max |p - p_ref| of the free bodies' positions (m)"
#: A single bouncing sphere: the larger of its final-position error and its apex error.
APEX_MEASURE = "max(|p - p_ref| at the end, |apex - apex_ref| of the first bounce) (m)"


@dataclass(frozen=True)
class Reference:
    """The reference run's final configuration ``q`` (the robot's joint positions, rad, or
    for a scene with free bodies their positions, m: ``measure`` says which), end-effector
    position (m; empty without a robot), its settings, the estimate of its own error: max
    |q_tight - q_loose| over two tolerances (or steps), its contact events and, for a
    single free sphere, the apex after its first impact (m; None otherwise) with its own
    error estimate (the same two runs' difference)."""

    spec: IntegratorSpec
    state_dim: int
    q: np.ndarray
    ee_position: np.ndarray
    error_estimate: float
    measure: str = JOINT_MEASURE
    events: tuple[ContactEvent, ...] = ()
    apex: float | None = None
    apex_estimate: float | None = None


@dataclass(frozen=True)
class SweepPoint:
    """One integrator setting's cost and accuracy (see the module docstring)."""

    integrator: str
    parameter: str
    value: float
    q_error: float
    ee_error: float
    energy_drift: float | None
    wall_time: float
    rhs_evals: int | None
    jac_evals: int | None
    work: float | None
    steps: int | None
    failure: str | None
    below_reference: bool = False
    event_error: float | None = None
    apex_error: float | None = None

    @property
    def spec(self) -> IntegratorSpec:
        """The integrator settings of this point (see :func:`spec_for`)."""
        return spec_for(self.integrator, self.value)

    def meets(self, target: float) -> bool:
        """Whether the run succeeded with a joint-space error of at most ``target`` (rad)."""
        return self.failure is None and self.q_error <= target


FIELDS = [f.name for f in dataclasses.fields(SweepPoint)]


def counted_work(rhs_evals: int | None, jac_evals: int | None, state_dim: int) -> float | None:
    """The cost model the recommendation ranks by: rhs evaluations plus Jacobian
    evaluations times the state dimension (a Jacobian costs as much as n rhs evaluations
    by finite differences). None when the backend does not report the rhs evaluations."""
    if rhs_evals is None:
        return None
    return float(rhs_evals + (jac_evals or 0) * state_dim)


def final_figures(simulator: Simulator, result: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    """Final configuration and end-effector position (m) of a run: with free bodies their
    final positions (m, (bodies x 3) flattened: a ball's landing, a box's sliding distance,
    a handed-over sphere's resting place) and no end effector, else the joint positions
    (rad) and the end effector."""
    q = result.x[-1, simulator.layout.slice("q")]
    if simulator.model.body_names:
        return simulator.model.body_motion(result.x[-1:])["position"][0].ravel(), np.zeros(0)
    return q, simulator.ee_pose_of(q)[:3, 3]


def check_sweepable(scene: Scene) -> None:
    """UserInputError (one line) for a scene with nothing that moves."""
    if not (scene.robot.nv or scene.free_bodies):
        raise UserInputError(f"scene {scene.name!r} has neither robot joints nor free bodies: nothing to sweep")


def reference_solution(scene: Scene) -> Reference:
    """The tight-tolerance reference and its error estimate from a 10x looser run."""
    check_sweepable(scene)
    if is_constrained(scene):   # the scene's stepper, refined
        method, value = scene.integrator.method, scene.integrator.dt / STEPPER_REFINEMENT
        values = (value, 2 * value)
    else:
        method = "radau" if scene.integrator.method != AUTO and REGISTRY[scene.integrator.method].stiff else "dop853"
        values = (REFERENCE_RTOL, 10 * REFERENCE_RTOL)
    finals, events, apexes = [], (), []
    for value in values:
        simulator = Simulator(scene, spec_for(method, value))
        result = simulator.run()
        finals.append(final_figures(simulator, result))
        events = events or tuple(result.contact_events)
        apexes.append(bounce_apex(simulator, result) if is_single_sphere(simulator) else None)
    (q, ee), (q_loose, _) = finals
    apex, apex_loose = apexes
    estimate = float(np.max(np.abs(q - q_loose)))
    if apex is not None:
        return Reference(spec_for(method, values[0]), simulator.state_dim, q, ee,
                         max(estimate, abs(apex - apex_loose)), APEX_MEASURE, events, apex, abs(apex - apex_loose))
    return Reference(spec_for(method, values[0]), simulator.state_dim, q, ee,
                     estimate, JOINT_MEASURE if ee.size else BODY_MEASURE, events)


def is_constrained(scene: Scene) -> bool:
    """Whether the scene has constraint-based contact (only the constraint steppers run it)."""
    return any(pair.law.law == "constraint" for pair in scene.contacts)


def default_grid(scene: Scene) -> dict[str, Sequence[float]]:
    """:data:`STEPPER_GRID` for a scene with constraint-based contact, else :data:`DEFAULT_GRID`."""
    return STEPPER_GRID if is_constrained(scene) else DEFAULT_GRID


def sweep_point(scene: Scene, method: str, value: float, reference: Reference) -> SweepPoint:
    """Run one setting and compare it with the reference."""
    spec = spec_for(method, value)
    parameter = "dt" if is_fixed_step(method) else "rtol"
    start = time.perf_counter()
    try:
        simulator = Simulator(scene, spec)
        result = simulator.run()
    except (IntegrationError, UserInputError) as error:   # diverged, or the method cannot run the scene
        return SweepPoint(method, parameter, value, math.nan, math.nan, None,
                          time.perf_counter() - start, None, None, None, None, str(error))
    q, ee = final_figures(simulator, result)
    stats = result.stats
    error = float(np.max(np.abs(q - reference.q)))
    apex_error = None
    if reference.apex is not None:
        apex_error = abs(bounce_apex(simulator, result) - reference.apex)
        apex_error = math.inf if math.isnan(apex_error) else apex_error   # it never bounced
        error = max(error, apex_error)
    return SweepPoint(method, parameter, value, error,
                      float(np.linalg.norm(ee - reference.ee_position)) if ee.size else math.nan, result.energy_error,
                      stats.wall_time, stats.rhs_evals, stats.jac_evals,
                      counted_work(stats.rhs_evals, stats.jac_evals, reference.state_dim), stats.steps, None,
                      error < reference.error_estimate,
                      event_time_difference(result.contact_events, reference.events) if reference.events else None,
                      apex_error)


def sweep(scene: Scene, reference: Reference, grid: dict[str, Sequence[float]] | None = None,
          progress: bool = True, *, workers: int | None = 0,
          scheduler: str | None = None) -> list[SweepPoint]:
    """Every integrator over its grid (default :data:`DEFAULT_GRID`), with a progress bar;
    the points are independent cases of :func:`~youbot_dynamics.accuracy.sweeps.map_cases`
    (serial with ``workers=0``, the default; a local cluster of ``workers`` processes, or
    the Dask cluster at ``scheduler``)."""
    grid = default_grid(scene) if grid is None else grid
    jobs = [(scene, method, value, reference) for method, values in grid.items() for value in values]
    return map_cases(sweep_point, jobs, workers=workers, scheduler=scheduler,
                     desc=f"work-precision {scene.name}", progress=progress)


def recommend(points: Iterable[SweepPoint], target_error: float) -> SweepPoint | None:
    """The point of least counted work whose joint-space error is at most
    ``target_error`` (rad); ties go to the registry's order, then to the looser setting.
    Wall time plays no part: the same sweep chooses the same on any machine. None if no
    point meets the target."""
    order = list(REGISTRY)
    meeting = [p for p in points if p.meets(target_error) and p.work is not None]
    if not meeting:
        return None
    return min(meeting, key=lambda p: (p.work, order.index(p.integrator), -p.value))


# ---------------------------------------------------------------------------------------
# Output files
# ---------------------------------------------------------------------------------------
def write_csv(points: Sequence[SweepPoint], path: Path) -> None:
    """The sweep as CSV, one row per point, columns :data:`FIELDS` (SI units)."""
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        writer.writeheader()
        for point in points:
            writer.writerow(dataclasses.asdict(point))


def _cell(value: float | int | None) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.3g}"
    return str(value)


def markdown_table(scene: Scene, reference: Reference, points: Sequence[SweepPoint],
                   best: SweepPoint | None = None, target_error: float | None = None) -> str:
    """The sweep as a markdown document: reference, one row per point, recommendation."""
    unit = "rad" if reference.measure == JOINT_MEASURE else "m"
    lines = [f"# Work-precision: {scene.name}", "",
             f"Scene `{scene.source}`, {scene.duration:g} s, state dimension "
             f"{reference.state_dim}, reference "
             f"{reference.spec.describe()} (own error estimate {reference.error_estimate:.2g} {unit}). "
             f"Error: {reference.measure}.", "",
             *apex_note(reference),
             f"| integrator | dt or rtol | error ({unit}) | EE error (m) | event times (s) | apex (m) "
             "| energy drift (J) | wall time (s) | rhs evals | Jacobians | work | steps | failure |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for p in points:
        failure = "" if p.failure is None else p.failure.replace("|", "/")[:80]
        error = f"< {reference.error_estimate:.3g} (ref)" if p.below_reference else _cell(p.q_error)
        ee = _cell(p.ee_error) if reference.ee_position.size else "-"
        lines.append(f"| {p.integrator} | {p.parameter}={p.value:g} | {error} | {ee} | {_cell(p.event_error)} "
                     f"| {_cell(p.apex_error)} | {_cell(p.energy_drift)} | {p.wall_time:.3g} | {_cell(p.rhs_evals)} | {_cell(p.jac_evals)} "
                     f"| {_cell(p.work)} | {_cell(p.steps)} | {failure} |")
    lines += ["", "Work: rhs evaluations + Jacobians x state dimension (counted, the same on any machine)."]
    if any(p.below_reference for p in points):
        lines += ["", "(ref): below the reference's own error estimate, so not resolved (the true error may be as "
                  "large as the estimate)."]
    if target_error is not None:
        lines += ["", f"Target error {target_error:g} {unit}: " +
                  ("no configuration meets it." if best is None else
                   f"cheapest is **{best.spec.describe()}** (work {best.work:.4g}, {best.wall_time:.3g} s, "
                   f"error {best.q_error:.2g} {unit}).")]
    return "\n".join(lines) + "\n"


def apex_note(reference: Reference) -> list[str]:
    """The markdown lines naming the reference's apex after the first impact (none
    without one)."""
    if reference.apex is None:
        return []
    return [f"Apex after the first impact: {reference.apex:.9g} m in the reference (own error estimate "
            f"{reference.apex_estimate:.2g} m); the apex column is |apex - apex_ref|.", ""]


def plot(scene: Scene, points: Sequence[SweepPoint], path: Path, measure: str = JOINT_MEASURE) -> None:
    """Work-precision PNG: wall time and rhs evaluations against the final error
    (``measure``: what it measures)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 2, figsize=(12, 5))
    for method in dict.fromkeys(p.integrator for p in points):
        good = [p for p in points if p.integrator == method and p.failure is None and p.q_error > 0]
        if not good:
            continue
        errors = [p.q_error for p in good]
        axes[0].loglog(errors, [p.wall_time for p in good], "o-", label=method)
        axes[1].loglog(errors, [p.rhs_evals or np.nan for p in good], "o-", label=method)
    for ax, label in zip(axes, ("wall time (s)", "rhs evaluations")):
        ax.set_xlabel(f"final error {measure}")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    figure.suptitle(f"work-precision: {scene.name} ({scene.duration:g} s)")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


@dataclass(frozen=True)
class WorkPrecision:
    """A finished study: reference, points, recommendation (if a target was given), files."""

    reference: Reference
    points: tuple[SweepPoint, ...]
    best: SweepPoint | None
    files: tuple[Path, ...]


def work_precision(scene: Scene, out_dir: str | Path, *, target_error: float | None = None,
                   grid: dict[str, Sequence[float]] | None = None, progress: bool = True,
                   workers: int | None = 0, scheduler: str | None = None) -> WorkPrecision:
    """Reference, sweep (``workers`` and ``scheduler`` as :func:`sweep`), CSV + markdown +
    PNG in ``out_dir``, and the recommendation."""
    if target_error is not None and not target_error > 0:
        raise UserInputError(f"--target-error must be positive (rad), got {target_error!r}")
    check_sweepable(scene)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    reference = reference_solution(scene)
    points = sweep(scene, reference, grid, progress, workers=workers, scheduler=scheduler)
    best = None if target_error is None else recommend(points, target_error)
    stem = out / f"work_precision_{scene.name}"
    files = (stem.with_suffix(".csv"), stem.with_suffix(".md"), stem.with_suffix(".png"))
    write_csv(points, files[0])
    files[1].write_text(markdown_table(scene, reference, points, best, target_error), encoding="utf-8")
    plot(scene, points, files[2], reference.measure)
    return WorkPrecision(reference, tuple(points), best, files)


# ---------------------------------------------------------------------------------------
# integrator: auto, chosen offline
# ---------------------------------------------------------------------------------------
def resolve_integrator(scene: Scene, *, grid: dict[str, Sequence[float]] | None = None,
                       progress: bool = True) -> IntegratorSpec:
    """The scene's integrator settings; for ``auto``, the sweep's recommendation for its
    ``target_error`` (a sweep per call: pin it with :func:`write_back` instead).
    UserInputError if no swept setting meets the target."""
    spec = scene.integrator
    if spec.method != AUTO:
        return spec
    best = recommend(sweep(scene, reference_solution(scene), grid, progress), spec.target_error)
    if best is None:
        raise SceneError(scene.source, "integrator.target_error", f"no swept configuration reaches "
                         f"{spec.target_error:g} rad on this scene")
    return dataclasses.replace(best.spec, energy_tolerance=spec.energy_tolerance, target_error=spec.target_error)


#: The integrator keys a write-back sets (every other key of the block is kept).
PINNED_KEYS = ("method", "dt", "tol", "rtol", "atol")
#: The comment a write-back puts above the keys it sets (an earlier one is replaced).
PIN_NOTE = "pinned by work-precision --write-back"
_TOP_KEY = re.compile(r"^integrator\s*:(?P<value>[^#]*?)\s*(?P<comment>#.*)?$")
_INNER_KEY = re.compile(r"^(?P<indent>\s+)(?P<key>[A-Za-z_]+)\s*:")


def yaml_scalar(value: Any) -> str:
    """A scalar as YAML reads it back: a float always with a dot (``1.0e-06``, never the
    string ``1e-06``), anything else as ``str`` gives it."""
    if not isinstance(value, float):
        return str(value)
    text = repr(value)
    mantissa, _, exponent = text.partition("e")
    if exponent and "." not in mantissa:
        text = f"{mantissa}.0e{exponent}"
    return text


def pinned_settings(spec: IntegratorSpec) -> dict[str, Any]:
    """The ``integrator`` keys that pin ``spec``: method and dt, or tol, or rtol and atol."""
    if spec.dt is not None:
        return {"method": spec.method, "dt": spec.dt}
    if spec.atol is None:
        return {"method": spec.method, "tol": spec.tol}
    return {"method": spec.method, "rtol": spec.rtol, "atol": spec.atol}


def with_integrator_block(text: str, settings: Mapping[str, Any], note: str) -> str:
    """The scene file's ``text`` with ``settings`` (PINNED_KEYS) in its top-level
    ``integrator`` block, after the comment ``# PIN_NOTE: note``: the block's other keys, its
    comments (but an earlier pin note) and every other line stay as they are; a flow mapping
    (``integrator: {...}``) becomes a block, a missing block is appended."""
    lines = text.splitlines()
    head = next((i for i, line in enumerate(lines) if _TOP_KEY.match(line)), None)
    if head is None:
        start, end, kept, indent, comment = len(lines), len(lines), [], "  ", ""
    else:
        match = _TOP_KEY.match(lines[head])
        comment = f"  {match['comment']}" if match["comment"] else ""
        end = block_end(lines, head)
        flow = match["value"].strip()
        kept, indent = _unpinned_lines(_flow_lines(flow) if flow else lines[head + 1:end])
        start, indent = head, indent or "  "
    values = [f"{indent}{key}: {yaml_scalar(value)}" for key, value in settings.items()]
    block = [f"integrator:{comment}", f"{indent}# {PIN_NOTE}: {note}", *values, *kept]
    return "\n".join(lines[:start] + block + lines[end:]) + "\n"


def block_end(lines: list[str], head: int) -> int:
    """The index after the last indented non-blank line of the block whose key is at line
    ``head`` (blank lines and top-level comments inside it do not end it)."""
    end = head + 1
    for j in range(head + 1, len(lines)):
        line = lines[j]
        if line[:1] in (" ", "\t") and line.strip():
            end = j + 1
        elif line.strip() and not line.startswith("#"):
            break
    return end


def _flow_lines(flow: str) -> list[str]:
    """A flow mapping's (``{method: ..., ...}``) keys as block lines."""
    data = read_yaml(flow.encode("utf-8"), "integrator")
    items = data.items() if isinstance(data, Mapping) else ()
    return [f"  {key}: {yaml_scalar(value)}" for key, value in items]


def _unpinned_lines(inner: list[str]) -> tuple[list[str], str | None]:
    """(the block's lines but its PINNED_KEYS and an earlier pin note; the indent of its
    first key, None without one)."""
    kept, indent = [], None
    for line in inner:
        found = _INNER_KEY.match(line)
        if found and indent is None:
            indent = found["indent"]
        if not (found and found["key"] in PINNED_KEYS or line.strip().startswith(f"# {PIN_NOTE}")):
            kept.append(line)
    return kept, indent


def write_back(path: str | Path, spec: IntegratorSpec, note: str) -> str:
    """Pin ``spec`` into the scene file at ``path`` (see :func:`with_integrator_block`),
    after checking that the edited file reads back as the same scene with that integrator;
    the file is replaced in one step. Returns the new text."""
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    settings = pinned_settings(spec)
    edited = with_integrator_block(text, settings, note)
    before, after = (read_yaml(t.encode("utf-8"), str(path)) for t in (text, edited))
    expected = {**{k: v for k, v in (before.get("integrator") or {}).items() if k not in PINNED_KEYS}, **settings}
    if {k: v for k, v in before.items() if k != "integrator"} != {k: v for k, v in after.items() if k != "integrator"} \
            or after.get("integrator") != expected:
        raise SceneError(str(path), "integrator", "the file's integrator block could not be edited safely; "
                         f"set it by hand to {settings}")
    Scene.from_dict(after, str(path), path.parent)  # still a valid scene
    replace_file(path, edited)
    return edited


def replace_file(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` in one step (a temporary file beside it, renamed), keeping
    the file's mode."""
    with tempfile.NamedTemporaryFile("w", encoding="utf-8", dir=path.parent, delete=False,
                                     prefix=f".{path.name}.") as handle:
        handle.write(text)
    try:
        os.chmod(handle.name, path.stat().st_mode)
        os.replace(handle.name, path)
    finally:
        Path(handle.name).unlink(missing_ok=True)
