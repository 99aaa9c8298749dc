"""Figures of the woodpecker toy (document 001 section 3, Figs 37-48; studies/woodpecker.py):
z (m) with the beak hits marked, phiS and phiB (rad), their rates (rad/s) and close-ups of
one period, the multipliers lambda (N), the mode sequence over time (s), and the bird's
phase portrait.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from youbot_dynamics.integrate.events import HybridSolution
from youbot_dynamics.studies.figures import FigureSet, panels, pyplot, save, specs
from youbot_dynamics.studies.woodpecker import (BEAK, MODES, SEED_BEAK_HITS, SEED_FIGURES,
                                                SEED_INITIAL_MODE, SEED_INITIAL_STATE, Woodpecker)


#: Document 001's initial lambda (N): its text's, and its Dymola listing's start values.
DOCUMENT_TEXT_LAMBDA0 = (-0.628993, 0.047088)
DOCUMENT_DYMOLA_LAMBDA0 = (-0.6911, -0.1416)


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
    seed_counts = (f"the document's {SEED_BEAK_HITS} beak hits; its state events "
                   + ", ".join(f"{name} {figures['events']}"
                               for name, figures in SEED_FIGURES.items()))
    drawn = {}
    for file, (label, column) in WOODPECKER_FILES.items():
        figure, axis = panels(size=(7.5, 3.2))
        axis.plot(solution.t, solution.x[:, column], linewidth=0.8)
        if column == 0:
            heights = np.interp(beak_times, solution.t, solution.x[:, 0])
            axis.plot(beak_times, heights, "rv", markersize=4,
                      label=f"ours: {hits} beak hits (document: {SEED_BEAK_HITS})")
            axis.legend(fontsize=7)
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
                       f"Against {seed_counts}. The document's curves carry no printed "
                       "numbers: compare the shape (a falling sleeve, a rocking bird).")
    drawn.update(draw_rates(out, solution, beak_times))
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
        f"Document: {SEED_BEAK_HITS} beak hits over 2 s, ours {hits}. Its state events count "
        "differently (IDA restarts, Dymola's crossings), so the switch counts are not "
        "one to one.")
    lambdas = np.array([woodpecker.constraint_forces(mode, x)
                        for mode, x in zip(solution.mode, solution.x)])
    figure, axis = panels(size=(7.5, 3.2))
    axis.plot(solution.t, lambdas[:, 0], linewidth=0.8, label="lambda1 (corner normal)")
    axis.plot(solution.t, lambdas[:, 1], linewidth=0.8, label="lambda2 (sticking)")
    axis.plot([0.0, 0.0], DOCUMENT_TEXT_LAMBDA0, "rx", markersize=7,
              label="document's text: lambda(0) = (-0.628993, 0.047088)")
    axis.plot([0.0, 0.0], DOCUMENT_DYMOLA_LAMBDA0, "k+", markersize=9,
              label="document's Dymola listing: (-0.6911, -0.1416)")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("N")
    axis.legend(fontsize=7)
    save(figure, out / "woodpecker_lambdas.png", "Woodpecker toy: constraint multipliers")
    start = woodpecker.constraint_forces(SEED_INITIAL_MODE, np.array(SEED_INITIAL_STATE))
    drawn["woodpecker_lambdas.png"] = (
        f"at the start ({SEED_INITIAL_MODE}): lambda = ({start[0]:.5g}, {start[1]:.5g}) N",
        "The document's text lists lambda0 = (-0.628993, 0.047088) N, which its state and "
        "parameters do not give; its own Dymola listing starts at (-0.6911, -0.1416) N, "
        "as ours (lambda follows from the state here).")
    figure, axis = panels(size=(5.5, 4.5))
    axis.plot(solution.x[:, 2], solution.x[:, 5], linewidth=0.5)
    axis.set_xlabel("phiB (rad)")
    axis.set_ylabel("phiB' (rad/s)")
    save(figure, out / "woodpecker_phase.png", "Woodpecker toy: the bird's phase portrait")
    drawn["woodpecker_phase.png"] = (
        f"phiB' from {solution.x[:, 5].min():.3g} to {solution.x[:, 5].max():.3g} rad/s; "
        "the beak hits are the vertical jumps at the right edge",
        "Not in the document: the limit cycle of the rocking bird, drawn from the same run.")
    return drawn


#: The close-up window of Figs 40 and 41 (s): one period of the motion.
CLOSE_UP = (1.0, 1.2)


def draw_rates(out: Path, solution: HybridSolution, beak_times: list[float]
               ) -> dict[str, tuple[str, str]]:
    """Fig. 39 (phiS', phiB' over 2 s) and Figs 40-41 (angles and rates over CLOSE_UP)."""
    drawn = {}
    window = (solution.t >= CLOSE_UP[0]) & (solution.t <= CLOSE_UP[1])
    figure, axis = panels(size=(7.5, 3.2))
    for column, name in ((4, "phiS'"), (5, "phiB'")):
        axis.plot(solution.t, solution.x[:, column], linewidth=0.6, label=name)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("angular velocity (rad/s)")
    axis.legend(fontsize=7)
    save(figure, out / "woodpecker_rates.png", "Woodpecker toy: phiS' and phiB' (Fig. 39)")
    drawn["woodpecker_rates.png"] = (
        f"phiB' in [{solution.x[:, 5].min():.3g}, {solution.x[:, 5].max():.3g}] rad/s, "
        f"phiS' in [{solution.x[:, 4].min():.3g}, {solution.x[:, 4].max():.3g}] rad/s",
        "Document Fig. 39: the rates jump at every beak hit; no numbers printed.")
    figure, axes = panels(2, 1, size=(7.5, 5.0))
    for column, name in ((1, "phiS"), (2, "phiB")):
        axes[0].plot(solution.t[window], solution.x[window, column], label=name)
    for column, name in ((4, "phiS'"), (5, "phiB'")):
        axes[1].plot(solution.t[window], solution.x[window, column], label=name)
    for axis in axes:
        for t in beak_times:
            if CLOSE_UP[0] <= t <= CLOSE_UP[1]:
                axis.axvline(t, color="red", linewidth=0.5)
        axis.legend(fontsize=7)
    axes[0].set_ylabel("angle (rad)")
    axes[1].set_ylabel("angular velocity (rad/s)")
    axes[1].set_xlabel("t (s); red: beak hits")
    save(figure, out / "woodpecker_close_up.png",
         f"Woodpecker toy over [{CLOSE_UP[0]:g}, {CLOSE_UP[1]:g}] s (Figs 40-41)")
    blocked = solution.x[window][np.isin(np.array(solution.mode)[window], ("II", "III")), 4]
    drawn["woodpecker_close_up.png"] = (
        f"phiS' while blocked (II, III): max |phiS'| {np.max(np.abs(blocked)):.2g} rad/s; "
        "phiB' changes sign at each beak hit",
        "As the document's Figs 40-41: the sleeve angle is constant while blocked (its rate "
        "0), the bird's rate jumps from positive to negative at a hit.")
    return drawn


WOODPECKER_SET = FigureSet("woodpecker", specs(
    ("woodpecker_z.png", "Woodpecker toy: sleeve height z(t) over 2 s, the beak hits marked",
     "Fig. 37 (22 beak hits over 2 s)."),
    ("woodpecker_phiS.png", "Woodpecker toy: sleeve angle phiS(t), the stops in grey",
     "Fig. 38 (phiS)."),
    ("woodpecker_phiB.png", "Woodpecker toy: bird angle phiB(t), the beak contact in red",
     "Fig. 38 (phiB)."),
    ("woodpecker_modes.png", "Woodpecker toy: the mode sequence I / II / III with the beak "
     "hits", "Fig. 48 (Dymola's states)."),
    ("woodpecker_lambdas.png", "Woodpecker toy: lambda1 and lambda2 over time",
     "Figs 42-43; the initial lambda (-0.628993, 0.047088) N of the text."),
    ("woodpecker_phase.png", "Woodpecker toy: phase portrait phiB' against phiB",
     "No figure in the document."),
    ("woodpecker_rates.png", "Woodpecker toy: phiS' and phiB' over 2 s", "Fig. 39."),
    ("woodpecker_close_up.png", "Woodpecker toy: angles and rates over one period",
     "Figs 40-41: the sleeve still while blocked, the bird's rate reversed at a hit."),
), draw_woodpecker)
