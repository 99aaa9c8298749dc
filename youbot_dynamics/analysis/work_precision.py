"""Speed versus accuracy on a scene: reference, sweep, tables, plot, recommendation.

- Reference: a tight-tolerance high-order run (DOP853 at rtol 1e-12, or Radau for scenes
  whose own integrator is implicit, i.e. stiff ones), checked by a second run at ten times
  the tolerance: their difference bounds the reference's own error (reported, and every
  sweep point is only as trustworthy as that figure).
- Sweep: each integrator over a grid of step sizes (fixed-step methods) or tolerances
  (adaptive ones, atol = rtol / 100). Per point: the final-state error in joint space
  (max_i |q_i - q_ref,i|, rad) and of the end-effector position (|p - p_ref|, m), the
  maximum energy drift max_t |E(t) - E(0)| (J) where the scene conserves energy, the wall
  time (s), the rhs evaluations, and the failure (a DivergenceError or IntegrationError
  message) if the run failed. The energy-growth check is off during the sweep (a drifting
  run is a data point, not a failure); non-finite states and the velocity bound stay on.
- Output: CSV, markdown table and a PNG work-precision plot (matplotlib Agg).
- ``recommend``: the cheapest point (wall time) whose joint-space error meets a target.
  ``resolve_integrator`` gives a scene with ``integrator: auto`` that recommendation,
  cached per scene under :func:`cache_dir` and keyed by the SHA-256 of the scene file's
  content and the target error: a changed scene file is swept again.
"""
from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from youbot_dynamics.analysis.sweeps import map_cases
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.sim.integrators import FIXED_STEP, IntegrationError
from youbot_dynamics.sim.scene import IntegratorSpec, Scene
from youbot_dynamics.sim.simulator import SimulationResult, Simulator

IMPLICIT = ("radau", "bdf", "cvode_bdf", "ida")
#: Step sizes (s) of the fixed-step methods and tolerances of the adaptive ones.
DEFAULT_GRID: dict[str, tuple[float, ...]] = {
    "euler": (1e-3, 3e-4, 1e-4, 3e-5),
    "symplectic_euler": (1e-3, 3e-4, 1e-4, 3e-5),
    "rk4": (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4),
    **{name: (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
       for name in ("rk45", "dop853", "radau", "bdf", "cvode_bdf", "cvode_adams", "ida")},
}
REFERENCE_RTOL = 1e-12
ATOL_PER_RTOL = 1e-2


def spec_for(method: str, value: float) -> IntegratorSpec:
    """The settings of one sweep point: dt = value (fixed step) or rtol = value,
    atol = value / 100; energy-growth check off."""
    if method in FIXED_STEP:
        return IntegratorSpec(method, dt=value, energy_tolerance=math.inf)
    return IntegratorSpec(method, rtol=value, atol=value * ATOL_PER_RTOL, energy_tolerance=math.inf)


@dataclass(frozen=True)
class Reference:
    """The reference run's final q (rad), end-effector position (m), its settings and the
    estimate of its own error (rad): max |q_tight - q_loose| over two tolerances."""

    spec: IntegratorSpec
    state_dim: int
    q: np.ndarray
    ee_position: np.ndarray
    error_estimate: float


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
    steps: int | None
    failure: str | None

    @property
    def spec(self) -> IntegratorSpec:
        """The integrator settings of this point (see :func:`spec_for`)."""
        return spec_for(self.integrator, self.value)

    def meets(self, target: float) -> bool:
        """Whether the run succeeded with a joint-space error of at most ``target`` (rad)."""
        return self.failure is None and self.q_error <= target


FIELDS = [f.name for f in dataclasses.fields(SweepPoint)]


def final_figures(simulator: Simulator, result: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    """Final joint positions (rad) and end-effector position (m) of a run."""
    q = result.x[-1, simulator.layout.slice("q")]
    return q, simulator.ee_pose_of(q)[:3, 3]


def reference_solution(scene: Scene) -> Reference:
    """The tight-tolerance reference and its error estimate from a 10x looser run."""
    method = "radau" if scene.integrator.method in IMPLICIT else "dop853"
    finals = []
    for rtol in (REFERENCE_RTOL, 10 * REFERENCE_RTOL):
        simulator = Simulator(scene, spec_for(method, rtol))
        finals.append(final_figures(simulator, simulator.run()))
    (q, ee), (q_loose, _) = finals
    return Reference(spec_for(method, REFERENCE_RTOL), simulator.state_dim, q, ee,
                     float(np.max(np.abs(q - q_loose))))


def sweep_point(scene: Scene, method: str, value: float, reference: Reference) -> SweepPoint:
    """Run one setting and compare it with the reference."""
    spec = spec_for(method, value)
    parameter = "dt" if method in FIXED_STEP else "rtol"
    simulator = Simulator(scene, spec)
    start = time.perf_counter()
    try:
        result = simulator.run()
    except IntegrationError as error:
        return SweepPoint(method, parameter, value, math.nan, math.nan, None,
                          time.perf_counter() - start, None, None, str(error))
    q, ee = final_figures(simulator, result)
    return SweepPoint(method, parameter, value, float(np.max(np.abs(q - reference.q))),
                      float(np.linalg.norm(ee - reference.ee_position)), result.energy_error,
                      result.stats.wall_time, result.stats.rhs_evals, result.stats.steps, None)


def sweep(scene: Scene, reference: Reference, grid: dict[str, Sequence[float]] | None = None,
          progress: bool = True, *, workers: int | None = 0,
          scheduler: str | None = None) -> list[SweepPoint]:
    """Every integrator over its grid (default :data:`DEFAULT_GRID`), with a progress bar;
    the points are independent cases of :func:`~youbot_dynamics.analysis.sweeps.map_cases`
    (serial with ``workers=0``, the default; a local cluster of ``workers`` processes, or
    the Dask cluster at ``scheduler``)."""
    grid = DEFAULT_GRID if grid is None else grid
    jobs = [(scene, method, value, reference) for method, values in grid.items() for value in values]
    return map_cases(sweep_point, jobs, workers=workers, scheduler=scheduler,
                     desc=f"work-precision {scene.name}", progress=progress)


def recommend(points: Iterable[SweepPoint], target_error: float) -> SweepPoint | None:
    """The cheapest point (least wall time, then fewest rhs evaluations) whose joint-space
    error is at most ``target_error`` (rad); None if none does."""
    meeting = [p for p in points if p.meets(target_error)]
    if not meeting:
        return None
    return min(meeting, key=lambda p: (p.wall_time, p.rhs_evals or 0))


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
    lines = [f"# Work-precision: {scene.name}", "",
             f"Scene `{scene.source}`, {scene.duration:g} s, state dimension "
             f"{reference.state_dim}, reference "
             f"{reference.spec.describe()} (own error estimate {reference.error_estimate:.2g} rad).", "",
             "| integrator | dt or rtol | q error (rad) | EE error (m) | energy drift (J) | wall time (s) "
             "| rhs evals | steps | failure |",
             "|---|---|---|---|---|---|---|---|---|"]
    for p in points:
        failure = "" if p.failure is None else p.failure.replace("|", "/")[:80]
        lines.append(f"| {p.integrator} | {p.parameter}={p.value:g} | {_cell(p.q_error)} | {_cell(p.ee_error)} "
                     f"| {_cell(p.energy_drift)} | {p.wall_time:.3g} | {_cell(p.rhs_evals)} | {_cell(p.steps)} "
                     f"| {failure} |")
    if target_error is not None:
        lines += ["", f"Target joint-space error {target_error:g} rad: " +
                  ("no configuration meets it." if best is None else
                   f"cheapest is **{best.spec.describe()}** ({best.wall_time:.3g} s, "
                   f"error {best.q_error:.2g} rad).")]
    return "\n".join(lines) + "\n"


def plot(scene: Scene, points: Sequence[SweepPoint], path: Path) -> None:
    """Work-precision PNG: wall time and rhs evaluations against joint-space error."""
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
        ax.set_xlabel("final joint-space error max|q - q_ref| (rad)")
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
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    reference = reference_solution(scene)
    points = sweep(scene, reference, grid, progress, workers=workers, scheduler=scheduler)
    best = None if target_error is None else recommend(points, target_error)
    stem = out / f"work_precision_{scene.name}"
    files = (stem.with_suffix(".csv"), stem.with_suffix(".md"), stem.with_suffix(".png"))
    write_csv(points, files[0])
    files[1].write_text(markdown_table(scene, reference, points, best, target_error), encoding="utf-8")
    plot(scene, points, files[2])
    return WorkPrecision(reference, tuple(points), best, files)


# ---------------------------------------------------------------------------------------
# integrator: auto
# ---------------------------------------------------------------------------------------
def cache_dir() -> Path:
    """$YOUBOT_DYNAMICS_CACHE, else ~/.cache/youbot_dynamics."""
    return Path(os.environ.get("YOUBOT_DYNAMICS_CACHE") or Path.home() / ".cache" / "youbot_dynamics")


def cache_path(scene: Scene, target_error: float) -> Path:
    """Where the recommendation for this scene content and target is cached."""
    return cache_dir() / "auto_integrator" / f"{scene.name}-{scene.content_hash[:20]}-{target_error:.3g}.json"


def resolve_integrator(scene: Scene, *, grid: dict[str, Sequence[float]] | None = None,
                       progress: bool = True) -> IntegratorSpec:
    """The scene's integrator settings; for ``auto``, the cached (or freshly swept)
    cheapest configuration meeting ``target_error``. UserInputError if none meets it."""
    spec = scene.integrator
    if spec.method != "auto":
        return spec
    path = cache_path(scene, spec.target_error)
    if path.is_file():
        cached = json.loads(path.read_text(encoding="utf-8"))
        return IntegratorSpec(**{**cached, "energy_tolerance": spec.energy_tolerance})
    reference = reference_solution(scene)
    best = recommend(sweep(scene, reference, grid, progress), spec.target_error)
    if best is None:
        raise UserInputError(f"{scene.source}: integrator.target_error: no swept configuration "
                             f"reaches {spec.target_error:g} rad on this scene")
    chosen = dataclasses.replace(best.spec, energy_tolerance=spec.energy_tolerance)
    path.parent.mkdir(parents=True, exist_ok=True)
    stored = {k: v for k, v in dataclasses.asdict(chosen).items() if k != "energy_tolerance"}
    path.write_text(json.dumps(stored), encoding="utf-8")
    return chosen
