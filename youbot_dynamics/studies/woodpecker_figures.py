"""Figures of the woodpecker toy (seed 001, Lund FMNN05 project 3; benchmarks.md section
2; studies/woodpecker.py): z (m), phiS and phiB (rad), the multipliers lambda (N) and the
mode sequence over time (s), and the bird's phase portrait.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from youbot_dynamics.integrate.events import HybridSolution
from youbot_dynamics.studies.figures import FigureSet, panels, pyplot, save, specs
from youbot_dynamics.studies.woodpecker import (BEAK, MODES, SEED_BEAK_HITS, SEED_FIGURES,
                                                SEED_INITIAL_MODE, SEED_INITIAL_STATE, Woodpecker)


def plot_woodpecker(woodpecker: Woodpecker, solution: HybridSolution, path: str) -> None:
    """Save a PNG (matplotlib, Agg) of z, phiS, phiB, lambda1, lambda2 and the mode index
    (I = 1, II = 2, III = 3) over time."""
    plt = pyplot()

    lambdas = np.array([woodpecker.constraint_forces(mode, x)
                        for mode, x in zip(solution.mode, solution.x)])
    index = [MODES.index(mode) + 1 for mode in solution.mode]
    rows = [("z (m)", solution.x[:, 0]), ("phiS (rad)", solution.x[:, 1]),
            ("phiB (rad)", solution.x[:, 2]), ("lambda1 (N)", lambdas[:, 0]),
            ("lambda2 (N)", lambdas[:, 1]), ("mode", index)]
    figure, axes = plt.subplots(len(rows), 1, sharex=True, figsize=(8, 9.5))
    for axis, (label, values) in zip(axes, rows):
        axis.plot(solution.t, values, linewidth=0.8)
        axis.set_ylabel(label)
        axis.grid(True, alpha=0.3)
    axes[-1].set_yticks([1, 2, 3], MODES)
    axes[-1].set_xlabel("t (s)")
    axes[0].set_title(f"Woodpecker toy: {solution.count(BEAK)} beak hits, "
                      f"{solution.stats.integrator}")
    save(figure, path)


#: The woodpecker's quantities drawn one per figure: file -> (label, column or key).
WOODPECKER_FILES = {"woodpecker_z.png": ("sleeve height z (m)", 0),
                    "woodpecker_phiS.png": ("sleeve angle phiS (rad)", 1),
                    "woodpecker_phiB.png": ("bird angle phiB (rad)", 2)}


def draw_woodpecker(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of WOODPECKER_SET."""
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
