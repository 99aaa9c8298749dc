"""Figures of the seed's two mechanisms (seed 001, Lund course): Andrew's squeezer in its
index-1, index-2 and index-3 forms (positions, velocities, multipliers, constraint drift;
benchmarks.md section 1) and the woodpecker toy (z, phiS, phiB, the multipliers and the
mode sequence; section 2).

The squeezer runs from the test set's consistent start with the seed's 500 outputs on
[0, 0.03] s: index 1 with RK45 (the seed's DOPRI5), index 2 with IDA, index 3 with Radau
IIA and Hairer's index-scaled error test (squeezer's default; the seed's IDA with the
algebraic variables out of the error test is in the squeezer-index3 table). Angles are
drawn wrapped to (-pi, pi], as the test set's plots show them.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from youbot_dynamics.studies.figures import FigureSet, panels, save, specs

#: Outputs of the squeezer runs (the seed's).
SQUEEZER_OUTPUTS = 500
#: formulation -> (our integrator, the seed's run of it: a key of squeezer.SEED_FIGURES).
SQUEEZER_RUNS = {"index1": ("rk45", "DOPRI5 index 1"),
                 "index2": ("ida", "Assimulo IDA index 2"),
                 "index3": ("radau5", "Assimulo IDA index 3")}


def seed_run_text(seed_run: str) -> str:
    """'DOPRI5 index 1: 85 steps, 704 f-evals' from squeezer.SEED_FIGURES."""
    from youbot_dynamics.studies.squeezer import SEED_FIGURES
    figures = SEED_FIGURES[seed_run]
    return f"{seed_run}: {figures['steps']} steps, {figures['rhs_evals']} f-evals"


def counts_difference(seed_run: str, stats) -> str:
    """Our steps and f-evals against the seed run's, in percent."""
    from youbot_dynamics.studies.squeezer import SEED_FIGURES
    figures = SEED_FIGURES[seed_run]
    return (f"Seed {seed_run}: {figures['steps']} steps, {figures['rhs_evals']} f-evals; ours "
            f"({stats.integrator}) {stats.steps} ({stats.steps / figures['steps'] - 1:+.0%}) "
            f"and {stats.rhs_evals} ({stats.rhs_evals / figures['rhs_evals'] - 1:+.0%})")
QUANTITIES = {"positions": "q mod 2 pi (rad)", "velocities": "v (rad/s)",
              "lambdas": "lambda (N or N m)"}


def wrapped(angles: np.ndarray) -> np.ndarray:
    """Angles wrapped to (-pi, pi]."""
    return np.angle(np.exp(1j * np.asarray(angles)))


def squeezer_quantity_plot(path: Path, run, quantity: str) -> None:
    """One quantity of one run over time, a line per component."""
    from youbot_dynamics.studies.squeezer import POSITION_NAMES
    values = {"positions": wrapped(run.q), "velocities": run.v,
              "lambdas": run.multipliers}[quantity]
    names = POSITION_NAMES if quantity != "lambdas" else [f"lambda{j + 1}" for j in range(6)]
    figure, axis = panels(size=(7.5, 3.8))
    for column, name in enumerate(names):
        axis.plot(run.t * 1e3, values[:, column], linewidth=0.8, label=name)
    axis.set_xlabel("t (ms)")
    axis.set_ylabel(QUANTITIES[quantity])
    if quantity == "lambdas":
        axis.set_yscale("symlog", linthresh=1.0)
    axis.legend(fontsize=7, ncol=4)
    save(figure, path, f"Andrew's squeezer, {run.formulation} with {run.stats.integrator}: "
                       f"{quantity}")


def draw_squeezer(out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of SQUEEZER_SET."""
    from youbot_dynamics.studies.squeezer import plot_drift, reference_error, simulate_squeezer
    runs = {formulation: simulate_squeezer(formulation, integrator,
                                           n_outputs=SQUEEZER_OUTPUTS)
            for formulation, (integrator, _) in SQUEEZER_RUNS.items()}
    drawn = {}
    for formulation, run in runs.items():
        stats = run.stats
        error = float(np.max(reference_error(run.q[-1])))
        drift = float(np.max(np.abs(run.position_residual)))
        for quantity in QUANTITIES:
            file = f"squeezer_{formulation}_{quantity}.png"
            squeezer_quantity_plot(out / file, run, quantity)
            figures = {"positions": f"q at 0.03 s off the reference by {error:.2g} (relative)",
                       "velocities": f"max |v| {np.max(np.abs(run.v)):.4g} rad/s",
                       "lambdas": "lambda at 0.03 s: " + ", ".join(
                           f"{value:.3g}" for value in run.multipliers[-1])}[quantity]
            drawn[file] = (
                f"{stats.integrator}: {stats.steps} steps, {stats.rhs_evals} f-evals; "
                f"{figures}; max |g(q)| {drift:.2g} m",
                counts_difference(SQUEEZER_RUNS[formulation][1], stats)
                + ("; Radau IIA with the index-scaled error test is another method than the "
                   "seed's IDA with the algebraic variables suppressed: the counts are not "
                   "comparable one to one" if formulation == "index3" else "") + ".")
    ode_runs = [runs["index1"]] + [simulate_squeezer(name, "rk45", n_outputs=SQUEEZER_OUTPUTS)
                                   for name in ("index1-baumgarte", "index1-projection")]
    plot_drift(ode_runs, str(out / "squeezer_drift.png"))
    drifts = {run.formulation: float(np.max(np.abs(run.position_residual)))
              for run in ode_runs}
    drawn["squeezer_drift.png"] = (
        "max |g(q)|: " + ", ".join(f"{name} {value:.2g} m" for name, value in drifts.items()),
        "The seed shows the drift of index 1 without stabilisation; Baumgarte and the "
        f"projection cut it by factors {drifts['index1'] / drifts['index1-baumgarte']:.2g} "
        f"and {drifts['index1'] / max(drifts['index1-projection'], 1e-300):.2g}.")
    plot_drift(list(runs.values()), str(out / "squeezer_drift_by_index.png"))
    drawn["squeezer_drift_by_index.png"] = (
        "at t = 0.03 s: " + "; ".join(
            f"{name} |g(q)| {np.max(np.abs(run.position_residual[-1])):.2g} m, "
            f"|G v| {np.max(np.abs(run.velocity_residual[-1])):.2g} m/s"
            for name, run in runs.items()),
        "The seed saw index 1 drift visibly with DOPRI5. Ours, at rtol 1e-6, drifts in "
        "position steadily over the run (index 1 and 2, whose position constraint is not "
        "enforced) while index 3 holds g(q) and lets G v wander instead.")
    return drawn


#: The woodpecker's quantities drawn one per figure: file -> (label, column or key).
WOODPECKER_FILES = {"woodpecker_z.png": ("sleeve height z (m)", 0),
                    "woodpecker_phiS.png": ("sleeve angle phiS (rad)", 1),
                    "woodpecker_phiB.png": ("bird angle phiB (rad)", 2)}


def draw_woodpecker(out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of WOODPECKER_SET."""
    from youbot_dynamics.studies.woodpecker import (BEAK, MODES, SEED_BEAK_HITS, SEED_FIGURES,
                                                    SEED_INITIAL_MODE, SEED_INITIAL_STATE,
                                                    Woodpecker)
    woodpecker = Woodpecker()
    solution = woodpecker.simulate(2.0, "dop853", rtol=1e-6, atol=1e-8,
                                   n_out=8000 if full else 4000)
    hits = solution.count(BEAK)
    beak_times = [s.time for s in solution.switches if s.kind == BEAK]
    counts = f"{hits} beak hits, {solution.stats.events} mode switches"
    seed_counts = (f"the seed's {SEED_BEAK_HITS} beak hits; its state events "
                   + ", ".join(f"{name} {figures['events']}"
                               for name, figures in SEED_FIGURES.items()))
    drawn = {}
    for file, (label, column) in WOODPECKER_FILES.items():
        figure, axis = panels(size=(7.5, 3.2))
        axis.plot(solution.t, solution.x[:, column], linewidth=0.8)
        if column == 2:
            axis.axhline(woodpecker.beak_angle(), color="red", linewidth=0.6,
                         label="beak touches the bar")
            axis.legend(fontsize=7)
        if column == 1:
            for sign in (1, -1):
                axis.axhline(sign * woodpecker.stop_angle(), color="grey", linewidth=0.6)
        axis.set_xlabel("t (s)")
        axis.set_ylabel(label)
        save(figure, out / file, f"Woodpecker toy: {label.split(' (')[0]}")
        values = solution.x[:, column]
        drawn[file] = (f"range [{values.min():.4g}, {values.max():.4g}]; {counts}",
                       f"Against {seed_counts}. The seed's curves are not in "
                       "benchmarks.md: compare the shape (a falling sleeve, a rocking bird).")
    figure, axis = panels(size=(7.5, 2.8))
    index = [MODES.index(mode) + 1 for mode in solution.mode]
    axis.step(solution.t, index, where="post", linewidth=0.8)
    for t in beak_times:
        axis.axvline(t, color="red", linewidth=0.4, alpha=0.6)
    axis.set_yticks([1, 2, 3], MODES)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("mode (red: beak hits)")
    save(figure, out / "woodpecker_modes.png", "Woodpecker toy: mode sequence")
    sequence = "".join({"I": "1", "II": "2", "III": "3"}[m] for m in
                       [solution.mode[0]] + [s.mode_after for s in solution.switches][:12])
    drawn["woodpecker_modes.png"] = (
        f"{counts}; the first modes {sequence}... (1 = I free, 2 = II, 3 = III)",
        f"Seed: {SEED_BEAK_HITS} beak hits over 2 s, ours {hits}. Its state events count "
        "differently (IDA restarts, Dymola's crossings), so the switch counts are not "
        "one to one.")
    lambdas = np.array([woodpecker.constraint_forces(mode, x)
                        for mode, x in zip(solution.mode, solution.x)])
    figure, axis = panels(size=(7.5, 3.2))
    axis.plot(solution.t, lambdas[:, 0], linewidth=0.8, label="lambda1 (corner normal)")
    axis.plot(solution.t, lambdas[:, 1], linewidth=0.8, label="lambda2 (sticking)")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("N")
    axis.legend(fontsize=7)
    save(figure, out / "woodpecker_lambdas.png", "Woodpecker toy: constraint multipliers")
    start = woodpecker.constraint_forces(SEED_INITIAL_MODE, np.array(SEED_INITIAL_STATE))
    drawn["woodpecker_lambdas.png"] = (
        f"at the start ({SEED_INITIAL_MODE}): lambda = ({start[0]:.5g}, {start[1]:.5g}) N",
        "The seed lists lambda0 = (-0.628993, 0.047088) N, which its own state and "
        "parameters do not give: ours follow from the state (lambda is no state here).")
    figure, axis = panels(size=(5.5, 4.5))
    axis.plot(solution.x[:, 2], solution.x[:, 5], linewidth=0.5)
    axis.set_xlabel("phiB (rad)")
    axis.set_ylabel("phiB' (rad/s)")
    save(figure, out / "woodpecker_phase.png", "Woodpecker toy: the bird's phase portrait")
    drawn["woodpecker_phase.png"] = (
        f"phiB' from {solution.x[:, 5].min():.3g} to {solution.x[:, 5].max():.3g} rad/s; "
        "the beak hits are the vertical jumps at the right edge",
        "Not in the seed: the limit cycle of the rocking bird, drawn from the same run.")
    return drawn


SQUEEZER_SET = FigureSet("squeezer", specs(
    *((f"squeezer_{formulation}_{quantity}.png",
       f"Andrew's squeezer, {formulation} ({integrator}): {quantity} over [0, 30] ms",
       f"The seed's {formulation.replace('index', 'index-')} {quantity} plot "
       f"({seed_run_text(seed)}).")
      for formulation, (integrator, seed) in SQUEEZER_RUNS.items() for quantity in QUANTITIES),
    ("squeezer_drift.png", "Constraint drift max |g(q)|, max |G v| of index 1: plain, "
     "Baumgarte, projection (RK45)", "The seed's drift figure of index 1 (visible drift)."),
    ("squeezer_drift_by_index.png", "Constraint drift of the index-1, index-2 and index-3 "
     "runs", "The seed's remark: index 1 drifts, index 2 and 3 do not (as much)."),
), draw_squeezer)

WOODPECKER_SET = FigureSet("woodpecker", specs(
    ("woodpecker_z.png", "Woodpecker toy: sleeve height z(t) over 2 s",
     "The seed's z plot (22 beak hits over 2 s)."),
    ("woodpecker_phiS.png", "Woodpecker toy: sleeve angle phiS(t), the stops in grey",
     "The seed's phiS plot."),
    ("woodpecker_phiB.png", "Woodpecker toy: bird angle phiB(t), the beak contact in red",
     "The seed's phiB plot."),
    ("woodpecker_modes.png", "Woodpecker toy: the mode sequence I / II / III with the beak "
     "hits", "The seed's mode sequence."),
    ("woodpecker_lambdas.png", "Woodpecker toy: lambda1 and lambda2 over time",
     "The seed's initial lambda (-0.628993, 0.047088) N."),
    ("woodpecker_phase.png", "Woodpecker toy: phase portrait phiB' against phiB",
     "No seed figure."),
), draw_woodpecker)
